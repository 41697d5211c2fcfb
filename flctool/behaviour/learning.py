"""The ``learning:`` section: one config model per learner, chosen by ``learner`` (paper Sec. IV).

:class:`LearningConfig` holds what every learner reads; each learner's model extends it with
its own keys and ``learner: Literal[name]``, and its plugin entry (:mod:`flctool.plugins`)
names that model, so ``learning:`` is the union of the models of every learner there is.
"""

from __future__ import annotations

from typing import Annotated, Any, ClassVar, Literal

from pydantic import BaseModel, ConfigDict, Field, ValidationInfo, field_validator, model_validator

from flctool.behaviour.base import Section
from flctool.behaviour.set_learning import SetLearningConfig

#: The learner of a ``learning:`` section that names none: the paper's method.
DEFAULT_LEARNER = "hybrid"


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
    hold: Annotated[int, Field(ge=1, strict=True)] | Literal["zeta", "auto"] | None = Field(
        None, description=(
            "how many of its firings a rule keeps a command it drew: 1 draws afresh every "
            "step (Glorennec & Jouffe's fuzzy Q-learning); n keeps it n firings; zeta keeps it "
            "a heavy-tailed number, n or more with probability 1/n (temporally-extended "
            "exploration); auto draws every step until the run has had no reward signal, then "
            "zeta, in fresh attempts with room for three; unset: auto, and 1 under protocol: "
            "paper"))


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
    episodes: int = Field(20, ge=1, description=(
        "validation episodes per candidate (a race's first round)"))
    # One default for the key every learner reads (an experiment's one file carries it for
    # all); what an unset key means is the learner's: LearningConfig.race_episodes.
    race: int | None = Field(None, ge=0, description=(
        "validation episodes a race takes its finalists to: when the run ends, the validated "
        "candidates race -- each round the best third (at least two) run on three times the "
        "episodes, up to this many -- and the winner is returned; 0 (or at most episodes): "
        "no race, the best on episodes is returned; unset: 60 under pitt and hybrid, 0 "
        "under fuzzy_q"))
    confirmation: int = Field(50, ge=0, description=(
        "fresh episodes the returned controller is confirmed on: the figure the run reports "
        "and stop.target is checked on (0: none)"))


class ExtendConfig(Section):
    """Going on past ``generations`` while the run still improves (docs/learning.md, "How
    long a run learns"): the run's budget sized by the problem as it is learned."""

    patience: int = Field(10, ge=1, description=(
        "past generations, the run goes on until its selected controller (the best validated "
        "one) has not improved for this many generations"))
    most: int | None = Field(None, ge=1, description=(
        "the most generations a run has in all; unset: from the problem, 30 for every 30 "
        "units of M log2 K (M rules to learn, K commands), and at least twice generations "
        "(docs/learning.md)"))


class TargetConfig(Section):
    """A target in the units a user reads: one of a success rate, a mean return, or a mean
    fitness (the learners' own figure)."""

    success: float | None = Field(None, ge=0, le=1, description=(
        "the confirmed success rate to reach, e.g. 0.95"))
    return_: float | None = Field(None, alias="return", description=(
        "the confirmed mean return (undiscounted) to reach, e.g. 475 on CartPole"))
    fitness: float | None = Field(None, description=(
        "the confirmed mean fitness to reach (what a plain number means)"))

    @model_validator(mode="after")
    def _one_unit(self) -> TargetConfig:
        given = [name for name in ("success", "return_", "fitness")
                 if getattr(self, name) is not None]
        if len(given) != 1:
            raise ValueError("give exactly one of success, return and fitness, e.g. "
                             "{success: 0.95}")
        return self

    @property
    def unit(self) -> str:
        """``success``, ``return`` or ``fitness``."""
        if self.success is not None:
            return "success"
        return "return" if self.return_ is not None else "fitness"

    @property
    def value(self) -> float:
        value = next(v for v in (self.success, self.return_, self.fitness) if v is not None)
        return float(value)


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
    target: float | TargetConfig | None = Field(None, description=(
        "stop once the selected controller's confirmation on fresh episodes reaches this: "
        "{success: 0.95}, {return: 475}, or a mean fitness ({fitness: 1.9}, or the number)"))

    def target_in_units(self) -> TargetConfig | None:
        """The target as a unit and a value (a plain number is a mean fitness)."""
        if self.target is None or isinstance(self.target, TargetConfig):
            return self.target
        return TargetConfig(fitness=self.target)


def _learner_required_unless_default(schema: dict[str, Any], model: type[Any]) -> None:
    # flctool reads a section without 'learner' as the default learner's, so in the JSON
    # Schema only that model may leave it out: editors then match a file to one model, as
    # flctool does.
    field = model.model_fields.get("learner")
    if field is not None and field.default != DEFAULT_LEARNER:
        required = schema.setdefault("required", [])
        if "learner" not in required:
            required.insert(0, "learner")


class LearningConfig(Section):
    """What every learner reads. Each learner's config extends it with its own keys and
    ``learner: Literal[name]``; a plugin's learner does the same (docs/plugins.md).

    Defaults are the paper's protocol: population 10, 30 generations, one trial each; a
    file that gives no budget learns with ``extend`` (and ``sized_trials``) instead.
    """

    model_config = ConfigDict(json_schema_extra=_learner_required_unless_default)

    learner: str = Field(DEFAULT_LEARNER, description=(
        "which learner reads this section; flctool learn --help lists the installed ones"))
    seed: int = Field(0, ge=0, description="seeds every random choice of the run")
    population: int = Field(10, ge=2, description=(
        "individuals per generation (fuzzy_q: a generation is population x trials episodes)"))
    generations: int = Field(30, ge=1, description=(
        "generations a run has; with extend, the least it has"))
    trials: int = Field(1, ge=1, description=(
        "trials per individual per generation; a file that gives no budget (protocol: auto) "
        "gets 2 under pitt and hybrid"))
    selection: SelectionConfig = SelectionConfig()
    stop: StopConfig = StopConfig()
    sets: SetLearningConfig | None = Field(None, description=(
        "learn the fuzzy sets of some inputs with the consequents (docs/learning.md); "
        "without it only the consequents are learned"))
    protocol: Literal["auto", "paper"] = Field("auto", description=(
        "paper: the paper's fixed budget, generations as given (30) and no extend; auto: "
        "a file that gives neither generations nor extend learns with extend's defaults"))
    extend: ExtendConfig | None = Field(None, description=(
        "go on past generations while the selected controller improves; set by default "
        "when the file gives no generations (protocol: auto)"))

    #: What an unset ``selection.race`` means for this learner. Measured (docs/learning.md):
    #: a race to 60 episodes lifts the GAs' worst seeds; fuzzy_q's greedy controllers of
    #: the latest generations are alike, and racing them changed nothing but the cost.
    default_race: ClassVar[int] = 60
    #: ``trials`` in the budget a file without one gets (with ``extend``): 1, the paper's.
    sized_trials: ClassVar[int] = 1
    #: Whether a run with ``extend`` runs all its ``extend.most`` generations instead of
    #: stopping once it no longer improves (a learner whose evidence only accumulates).
    runs_to_most: ClassVar[bool] = False

    @model_validator(mode="before")
    @classmethod
    def _budget_from_the_problem(cls, data: Any) -> Any:
        # A file that says nothing of its budget gets one sized as it learns (extend, and
        # the learner's sized_trials unless it gives trials); one that gives generations,
        # or protocol: paper, gets exactly what it says. Decided on the data as written, so
        # a run directory's resolved file (which writes every key) reads back the same.
        if not isinstance(data, dict):
            return data
        if data.get("protocol") == "paper":
            if data.get("extend") is not None:
                raise ValueError("protocol: paper is the paper's fixed budget, without "
                                 "extend; leave one of them out")
            return data
        if "generations" not in data and "extend" not in data:
            sized = {**data, "extend": {}}
            if "trials" not in data and cls.sized_trials != 1:
                sized["trials"] = cls.sized_trials
            return sized
        return data

    @field_validator("stop")
    @classmethod
    def _room_for_a_generation(cls, stop: StopConfig, info: ValidationInfo) -> StopConfig:
        # the budget is checked between generations, so a limit below one generation's
        # episodes would be broken by the first
        population, trials = info.data.get("population"), info.data.get("trials")
        if stop.episodes is not None and population is not None and trials is not None \
                and stop.episodes < population * trials:
            raise ValueError(f"episodes: {stop.episodes} cannot pay for one generation, which "
                             f"takes {population * trials} (population {population} x trials "
                             f"{trials}); raise it, or lower the population or the trials")
        return stop

    @property
    def race_episodes(self) -> int:
        """``selection.race`` as the run reads it: the file's, or the learner's default."""
        return self.default_race if self.selection.race is None else self.selection.race


class GeneticConfig(LearningConfig):
    """The genetic algorithm's keys, shared by the ``pitt`` and ``hybrid`` learners
    (paper Sec. IV: pc 0.2, pm 0.1, one elite)."""

    #: Two trials per individual when the file gives no budget: one success or failure is
    #: a noisy measure of a controller, and a second halves its variance. Measured on the
    #: task suite's development seeds (docs/learning.md, "How long a run learns"): it lifts
    #: the worst seeds of most pitch tasks (approach 0.682 -> 0.798, dribble 0.893 ->
    #: 0.957) for about 1.4x the episodes; the paper's protocol keeps one.
    sized_trials: ClassVar[int] = 2

    crossover: float = Field(0.2, ge=0, le=1, description="crossover probability pc")
    mutation: float = Field(0.1, ge=0, le=1, description="mutation probability pm, per gene")
    elites: int = Field(1, ge=0, description="best individuals copied unchanged")
    common_starts: bool = Field(False, description=(
        "every individual of a generation gets the same start states"))
    # One default for the key both GA learners read (an experiment's one file carries it
    # for both); what an unset key means is the learner's: `restarts_after`.
    restart_after: int | None = Field(None, ge=0, description=(
        "generations without a better selected controller after which every individual but "
        "the elites is drawn afresh (premature convergence); 0: never, as in the paper; "
        "unset: 5 under hybrid, 0 under pitt"))

    #: What an unset ``restart_after`` means for this learner.
    default_restart_after: ClassVar[int] = 0

    @property
    def restarts_after(self) -> int:
        """``restart_after`` as the learner reads it: the file's, or the learner's default."""
        return self.default_restart_after if self.restart_after is None else self.restart_after

    @field_validator("elites")
    @classmethod
    def _room_to_evolve(cls, elites: int, info: ValidationInfo) -> int:
        population = info.data.get("population")
        if population is not None and elites >= population:
            raise ValueError(f"{elites} elites in a population of {population} copy every "
                             "individual unchanged, so nothing evolves; keep elites below "
                             "the population (the paper copies 1)")
        return elites


class PittConfig(GeneticConfig):
    """``learner: pitt``: the GA alone, learning from fitness only."""

    learner: Literal["pitt"] = Field("pitt", description=(
        "the Pitt approach: a GA over whole controllers"))
    pitt_crossover: Literal["uniform", "one_point"] = Field("uniform", description=(
        "how two parents make a child: each gene from either (uniform) or one cut point"))


class FuzzyQConfig(LearningConfig):
    """``learner: fuzzy_q``: fuzzy Q-learning of one controller (eq. 4-9)."""

    learner: Literal["fuzzy_q"] = Field("fuzzy_q", description="fuzzy Q-learning of one controller")
    q: QConfig = QConfig()
    exploration: ExplorationConfig = ExplorationConfig()

    default_race: ClassVar[int] = 0

    @property
    def hold(self) -> int | Literal["zeta", "auto"]:
        """``exploration.hold`` as the run reads it: the file's, else ``auto`` (measured in
        docs/learning.md, "How long a rule holds an explored command"), or a fresh draw every
        step under the paper's protocol, as published."""
        if self.exploration.hold is not None:
            return self.exploration.hold
        return 1 if self.protocol == "paper" else "auto"


class HybridConfig(GeneticConfig):
    """``learner: hybrid``, the paper's method: the GA guided by fuzzy-Q rule strengths."""

    learner: Literal["hybrid"] = Field("hybrid", description=(
        "the paper's method: the GA guided by fuzzy-Q rule strengths (the default)"))
    q: QConfig = QConfig()
    greedy_individual: bool = Field(True, description=(
        "every generation after the first holds the q table's greedy controller (each rule's "
        "strongest command) in place of one bred child; false: as in the paper"))
    # Measured (docs/learning.md): restarts lift the hybrid's worst seeds, whose q-guided
    # operators can lock a population onto a poor table; they lower Pitt's.
    default_restart_after: ClassVar[int] = 5


class CreditConfig(LearningConfig):
    """``learner: credit``: rule tables drawn from each rule's credit, every episode's outcome
    shared among the rules that fired (:mod:`flctool.learners.credit`)."""

    learner: Literal["credit"] = Field("credit", description=(
        "rule-wise credit: tables drawn by Thompson sampling from each rule's credit, pooled "
        "over every episode of every table"))
    population: int = Field(100, ge=2, description=(
        "rule tables drawn per generation, each run for trials episodes"))
    prior: float = Field(1.0, gt=0, description=(
        "pseudo-episodes of no credit every rule and command starts with: how much evidence "
        "a command needs before its credit counts"))

    default_race: ClassVar[int] = 0
    runs_to_most: ClassVar[bool] = True

    @field_validator("sets")
    @classmethod
    def _consequents_only(cls, sets: SetLearningConfig | None) -> SetLearningConfig | None:
        if sets is not None:
            raise ValueError("the credit learner learns rule consequents only, not sets; learn "
                             "the sets with hybrid, pitt or fuzzy_q")
        return sets


def learner_keys(model: type[BaseModel]) -> tuple[str, ...]:
    """The keys a ``learning:`` model reads, as a file writes them."""
    return tuple(info.alias or name for name, info in model.model_fields.items())
