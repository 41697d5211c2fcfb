"""One trial (episode) of one controller: the hot loop every learner shares.

All three learners spend nearly all their time here, so the loop works on plain Python floats
and lists: with overlapping trapezoids only 2-4 of the M rules fire per state, and numpy's
per-call overhead (and array conversions) on lists that small costs more than the arithmetic.
Everything the loop needs is passed in explicitly, so it can be replaced by a compiled version
without touching the learners.

The crisp output is computed with exactly the operations of :meth:`Controller.output` (both
sums accumulated left to right in rule order, then one division), so the controller acts
during learning bit for bit as the deployed one does.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from typing import Protocol

from flctool.compile import Controller
from flctool.compile.defuzzify import centre_of_area
from flctool.compile.membership import firing_sets
from flctool.envs.base import BatchEnv
from flctool.errors import InferenceError


class SparseRules:
    """The rule base of a controller as plain Python data, evaluated one state at a time.

    Gives exactly the activations of :meth:`Controller.active_rules` (same formulas, same
    floating-point operations), normalised to phi_m = alpha_m / sum(alpha) (eq. 7).
    """

    def __init__(self, controller: Controller) -> None:
        self.n_rules = controller.n_rules
        self.n_commands = controller.n_commands
        self.singletons: list[float] = [float(v) for v in controller.singletons]
        self._names = controller.input_names
        self._low, self._high = min(self.singletons), max(self.singletons)
        self._lows = [float(v) for v in controller.ranges[:, 0]]
        self._highs = [float(v) for v in controller.ranges[:, 1]]
        self._sets = [[tuple(float(v) for v in quad) for quad in quads]
                      for quads in controller.quadruples]

    def fire(self, state: list[float]) -> tuple[list[int], list[float], list[float]]:
        """Active rules of one state (N,) in increasing order, their activations alpha_m
        (eq. 2), and phi_m = alpha_m / sum(alpha) (eq. 7)."""
        rules, alphas, total = self.activations(state)
        return rules, alphas, [a / total for a in alphas]

    def activations(self, state: list[float]) -> tuple[list[int], list[float], float]:
        """Active rules of one state (N,) in increasing order, their activations alpha_m
        (eq. 2), and sum(alpha) added in rule order (the denominator of eq. 3 and eq. 7)."""
        if len(state) != len(self._sets):
            raise InferenceError(f"the state has {len(state)} values for "
                                 f"{len(self._sets)} inputs")
        rules = [0]
        alphas = [1.0]
        for i, value in enumerate(state):
            if value != value:  # NaN: every comparison below would be false
                raise InferenceError(f"the environment observed NaN for input "
                                     f"'{self._names[i]}'",
                                     hint="NaN has no membership; fix the adapter's sensor")
            low, high, sets = self._lows[i], self._highs[i], self._sets[i]
            s = low if value < low else high if value > high else value  # clip to the range
            members = firing_sets(s, sets)  # (index, mu > 0) in set order
            if i == 0:  # the first input: min(1.0, mu) is mu, as 0 < mu <= 1
                rules = [j for j, _ in members]
                alphas = [mu for _, mu in members]
            else:
                width = len(sets)
                rules = [r * width + j for r in rules for j, _ in members]
                alphas = [a if a < mu else mu for a in alphas for _, mu in members]
        total = add_in_order(alphas)
        if not total > 0.0:  # covered ranges fire a rule; only underflow leaves none
            raise InferenceError(f"no rule fires for the state {state}: the sets overlap too "
                                 "little to be computed in floating point",
                                 hint="widen the sets' overlap")
        return rules, alphas, total

    def output(self, alphas: list[float], commands: list[int]) -> float:
        """Crisp output of eq. 3 from the firing rules' activations and command indices."""
        return self.clip(centre_of_area(zip(alphas, map(self.singletons.__getitem__, commands),
                                            strict=True), 0.0))

    def clip(self, value: float) -> float:
        """Within the commands, as Controller.output keeps it (rounding may step an ulp
        past)."""
        return self._low if value < self._low else self._high if value > self._high else value

    def vote(self, alphas: list[float], commands: list[int]) -> float:
        """The action mode ``vote``: each command's firing rules sum their activations (in
        rule order) and the singleton of the strongest command is the output; ties go to
        the command listed first. Exactly what :func:`flctool.rollout.vote_output` gives."""
        totals = [0.0] * self.n_commands
        for a, k in zip(alphas, commands, strict=True):
            totals[k] += a
        best = 0
        for k in range(1, self.n_commands):
            if totals[k] > totals[best]:
                best = k
        return self.singletons[best]


def add_in_order(values: Iterable[float]) -> float:
    """Plain left-to-right addition from 0.0, as the compiled kernels do.

    Every sum that a run's results depend on goes through here: Python >= 3.12's builtin
    ``sum()`` of floats is compensated and rounds differently, so using it would make runs
    differ between Python versions.
    """
    total = 0.0
    for value in values:
        total += value
    return total


class Chooser(Protocol):
    """Picks each firing rule's command for one step (exploration of ``fuzzy_q``)."""

    def choose(self, rules: list[int]) -> list[int]: ...


class TemporalDifference(Protocol):
    """Learns from one step (eq. 6-9); see :class:`flctool.learners.fuzzy_q.FuzzyQ`."""

    def reset_traces(self) -> None: ...

    def learn(self, rules: list[int], phi: list[float], commands: list[int], reward: float,
              next_rules: list[int], next_phi: list[float], terminal: bool) -> float: ...


@dataclass(frozen=True)
class Trial:
    """The outcome of one episode."""

    ret: float  # undiscounted return
    length: int  # steps taken
    success: bool


def run_trial(env: BatchEnv, rules: SparseRules, seed: int, consequents: list[int] | None,
              chooser: Chooser | None = None, td: TemporalDifference | None = None,
              acted: set[int] | None = None) -> Trial:
    """Run one episode from ``seed`` on a batch-of-one ``env``.

    The commands come from the fixed ``consequents (M,)`` (pitt, hybrid) or, step by step, from
    ``chooser`` (fuzzy_q). With ``td``, every step updates the q table (eq. 4-9): trial after
    trial, never summed over simultaneous episodes. A terminal step does not bootstrap; a
    truncated one does (the time limit is not part of the task). ``acted`` collects the rules
    that fired in a state the controller acted on: only their commands shaped the episode.
    """
    if chooser is None:
        if consequents is None:
            raise ValueError("run_trial needs consequents or a chooser")
        if td is None and not env.votes:
            return _fixed_trial(env, rules, seed, consequents, acted)
    if td is not None:
        td.reset_traces()
    # The B = 1 fast path of the adapter protocol: the same results as reset/step on arrays
    # of one, without building them every step.
    active, alphas, total = rules.activations(env.reset_one(seed).tolist())
    # phi (eq. 7) only for the q update; each state's is computed once
    phi = [a / total for a in alphas] if td is not None else []
    votes = env.votes
    ret = 0.0
    steps = 0
    while True:
        if acted is not None:
            acted.update(active)
        if chooser is not None:
            commands = chooser.choose(active)
        else:
            commands = [consequents[m] for m in active]  # type: ignore[index]
        # eq. 3, or the vote
        action = rules.vote(alphas, commands) if votes else rules.output(alphas, commands)
        observation, reward, terminal, truncated = env.step_one(action)
        ret += reward
        steps += 1
        if terminal:
            next_active: list[int] = []
            next_alphas: list[float] = []
            next_phi: list[float] = []
        else:
            next_active, next_alphas, total = rules.activations(observation.tolist())
            next_phi = [a / total for a in next_alphas] if td is not None else []
        if td is not None:
            td.learn(active, phi, commands, reward, next_active, next_phi, terminal)
        if terminal or truncated:
            return Trial(ret, steps, bool(env.success()[0]))
        active, alphas, phi = next_active, next_alphas, next_phi


def _fixed_trial(env: BatchEnv, rules: SparseRules, seed: int, consequents: list[int],
                 acted: set[int] | None) -> Trial:
    """:func:`run_trial` with fixed consequents, no q update and eq. 3 (pitt's trials and
    every validation episode): the same operations with less bookkeeping per step."""
    # each rule's command singleton, so eq. 3 needs no command list
    singleton = [rules.singletons[k] for k in consequents].__getitem__
    clip = rules.clip
    active, alphas, _ = rules.activations(env.reset_one(seed).tolist())
    ret = 0.0
    steps = 0
    while True:
        if acted is not None:
            acted.update(active)
        action = clip(centre_of_area(zip(alphas, map(singleton, active), strict=True), 0.0))
        observation, reward, terminal, truncated = env.step_one(action)
        ret += reward
        steps += 1
        if terminal:
            return Trial(ret, steps, bool(env.success()[0]))
        # a truncated episode's last state is fired too, as run_trial does (its errors count)
        active, alphas, _ = rules.activations(observation.tolist())
        if truncated:
            return Trial(ret, steps, bool(env.success()[0]))
