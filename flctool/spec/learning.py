"""The ``learning:`` section: which learner, and its hyperparameters (paper Sec. IV)."""

from __future__ import annotations

from typing import Literal

from pydantic import Field, ValidationInfo, field_validator

from flctool.registry import did_you_mean
from flctool.spec.base import Section

#: The built-in learners (flctool.plugins adds installed ones).
LEARNER_NAMES = ("pitt", "fuzzy_q", "hybrid")


class QConfig(Section):
    """Fuzzy Q-learning (eq. 4-9)."""

    alpha: float = Field(0.1, gt=0, le=1, description="learning rate of eq. 7")
    gamma: float = Field(0.9, ge=0, le=1, description="discount factor of eq. 6")
    lambda_: float = Field(0.7, ge=0, le=1, alias="lambda",
                           description="eligibility trace decay of eq. 8 (0: one-step)")
    temperature: float = Field(0.15, gt=0, description=(
        "Boltzmann temperature over rule strengths (hybrid mutation, fuzzy_q exploration)"))
    initial: float = Field(0.0, description="initial value of every q")


class ExplorationConfig(Section):
    """How ``fuzzy_q`` picks each rule's consequent during a trial."""

    policy: Literal["boltzmann", "epsilon_greedy"] = "boltzmann"
    epsilon: float = Field(0.1, ge=0, le=1, description="epsilon of epsilon_greedy")
    decay: float = Field(1.0, gt=0, le=1, description=(
        "multiplies temperature (boltzmann) or epsilon (epsilon_greedy) after each generation"))
    minimum: float = Field(0.0, ge=0, description="floor of the decayed temperature or epsilon")


class SelectionConfig(Section):
    """Model selection: which controller of the run becomes ``best.yaml`` (docs/learning.md).

    Candidates (the best distinct controllers seen, by training fitness; for ``fuzzy_q`` the
    greedy controller of the latest generations) are re-run on validation episodes whose seeds
    no training episode and no ``flctool evaluate`` uses; the best validated one is returned.
    Validation episodes count in the run's budget.
    """

    candidates: int = Field(10, ge=0, description=(
        "controllers kept for validation (0: no selection, best.yaml is the last "
        "generation's best by its training trials)"))
    episodes: int = Field(20, ge=1, description="validation episodes per candidate")


class StopConfig(Section):
    """Budgets that end a run before ``generations``; every one counts training and
    validation episodes alike, and is checked between generations."""

    episodes: int | None = Field(None, ge=1, description=(
        "at most this many episodes in all (never exceeded)"))
    steps: int | None = Field(None, ge=1, description=(
        "environment steps in all; the run stops when the next generation would likely "
        "exceed it"))
    seconds: float | None = Field(None, gt=0, description=(
        "training time; the run stops after the generation that used it up (not "
        "reproducible: resumed runs may stop elsewhere)"))
    target: float | None = Field(None, description=(
        "stop once a controller's validated mean fitness reaches this"))


class LearningConfig(Section):
    """Defaults are the paper's protocol: population 10, pc 0.2, pm 0.1, 30 generations."""

    learner: str = Field("hybrid", description=(
        "one of: " + ", ".join(LEARNER_NAMES) + ", or an installed plugin's"))
    seed: int = Field(0, ge=0, description="seeds every random choice of the run")
    population: int = Field(10, ge=2)
    generations: int = Field(30, ge=1)
    crossover: float = Field(0.2, ge=0, le=1, description="crossover probability pc")
    mutation: float = Field(0.1, ge=0, le=1, description="mutation probability pm, per gene")
    pitt_crossover: Literal["uniform", "one_point"] = Field("uniform", description=(
        "the pitt learner's crossover (the hybrid takes, gene by gene, the stronger rule)"))
    elites: int = Field(1, ge=0, description="best individuals copied unchanged")
    trials: int = Field(1, ge=1, description="trials per individual per generation")
    common_starts: bool = Field(False, description=(
        "every individual of a generation gets the same start states"))
    q: QConfig = QConfig()
    exploration: ExplorationConfig = ExplorationConfig()
    selection: SelectionConfig = SelectionConfig()
    stop: StopConfig = StopConfig()

    @field_validator("elites")
    @classmethod
    def _room_to_evolve(cls, elites: int, info: ValidationInfo) -> int:
        population = info.data.get("population")
        if population is not None and elites >= population:
            raise ValueError(f"{elites} elites in a population of {population} copy every "
                             "individual unchanged, so nothing evolves; keep elites below "
                             "the population (the paper copies 1)")
        return elites

    @field_validator("learner")
    @classmethod
    def _known_learner(cls, name: str) -> str:
        from flctool.plugins import names

        known = names("learner")
        if name not in known:
            raise ValueError(f"unknown learner '{name}'.{did_you_mean(name, known)} "
                             f"Use one of: {', '.join(known)}")
        return name
