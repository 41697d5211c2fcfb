"""The fuzzy controller's parts of a behaviour file (paper Sec. II): the inputs with their
fuzzy sets, the output with its singleton commands, and the rules of eq. 1.

Each is a model of its own, checked for its structure and types; what relates them to each
other (coverage, rule references) is checked by :mod:`flctool.behaviour.checks` when the whole
behaviour (:class:`flctool.behaviour.models.Behaviour`) is validated.
"""

from __future__ import annotations

from typing import Annotated, Any, Union

from pydantic import AfterValidator, ConfigDict, Discriminator, Field, Tag

from flctool.behaviour.base import Name, Section
from flctool.behaviour.shapes import ShapedSet


def _ordered(quad: tuple[float, float, float, float]) -> tuple[float, float, float, float]:
    pa, pb, pc, pd = quad
    if not pa <= pb <= pc <= pd:
        raise ValueError(
            f"the quadruple [{pa:g}, {pb:g}, {pc:g}, {pd:g}] must satisfy pa <= pb <= pc <= pd; "
            "write the left foot, left shoulder, right shoulder, right foot in that order")
    return quad


Quadruple = Annotated[tuple[float, float, float, float], AfterValidator(_ordered)]


def _set_form(value: Any) -> str:
    return "shape" if isinstance(value, (dict, ShapedSet)) else "trapezoid"


#: A set: a trapezoid quadruple (the default, and the paper's), or a shape written as a
#: one-key mapping (flctool.behaviour.shapes). The form of the value chooses, so an error
#: concerns the form written.
FuzzySet = Annotated[Union[Annotated[Quadruple, Tag("trapezoid")],  # noqa: UP007
                           Annotated[ShapedSet, Tag("shape")]], Discriminator(_set_form)]


def _increasing(bounds: tuple[float, float]) -> tuple[float, float]:
    lo, hi = bounds
    if not lo < hi:
        raise ValueError(f"range [{lo:g}, {hi:g}] must be [low, high] with low < high")
    return bounds


def _range_may_default(schema: dict[str, Any]) -> None:
    # The loader fills in a gymnasium input's range before validation
    # (default_gymnasium_ranges), so a file may leave it out: editors must not flag that.
    schema["required"] = [key for key in schema.get("required", []) if key != "range"]


class InputVariable(Section):
    """One sensor input s_i with its L_i fuzzy sets."""

    model_config = ConfigDict(json_schema_extra=_range_may_default)

    range: Annotated[tuple[float, float], AfterValidator(_increasing)] = Field(
        description="[low, high]; inputs outside it are clipped to it. Required, except "
        "for a gymnasium input whose observation bounds are finite: it defaults to them "
        "(docs/environments.md)")
    unit: str | None = None
    sets: dict[Name, FuzzySet] = Field(min_length=1, description=(
        "set name -> [pa, pb, pc, pd] (a trapezoid; pb == pc is a triangle, pa == pb or "
        "pc == pd a vertical edge), or a shape {gauss: [mean, sigma]}, {gauss2: [...]}, "
        "{bell: [width, slope, centre]}, {sigmoid: [centre, slope]}, {sigmoid_difference: "
        "[...]}, {sigmoid_product: [...]}, {s_shape: [foot, shoulder]}, {z_shape: "
        "[shoulder, foot]}, {pi_shape: [...]}, {cosine: [centre, width]}, {concave: "
        "[inflection, end]} or {spike: [centre, width]} (docs/behaviour-files.md)"))


class Output(Section):
    """The single output a, with its K singleton commands c^k."""

    name: Name
    unit: str | None = None
    commands: dict[Name, float] = Field(min_length=1, description="command name -> singleton")


class Rule(Section):
    """Rule R_m of eq. 1: IF s_1 is F^{j_1} AND ... THEN a is c^k."""

    if_: dict[Name, Name] = Field(alias="if", min_length=1)
    then: Name
