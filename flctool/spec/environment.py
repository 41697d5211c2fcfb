"""The ``environment:`` section: one config model per adapter, chosen by ``adapter``."""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import Field

from flctool.spec.base import Section


class BallchaseSimConfig(Section):
    """The ballchase simulator of paper Sec. IV."""

    adapter: Literal["ballchase-sim"]
    max_steps: int = Field(200, ge=1, description="steps before an episode is truncated")


class GymnasiumConfig(Section):
    """Any Gymnasium environment with a Box observation space."""

    adapter: Literal["gymnasium"]
    id: str = Field(description="a registered Gymnasium id, e.g. CartPole-v1")
    max_steps: int | None = Field(None, ge=1)


EnvironmentConfig = Annotated[
    BallchaseSimConfig | GymnasiumConfig,
    Field(discriminator="adapter"),
]
ADAPTER_NAMES = ("ballchase-sim", "gymnasium")
