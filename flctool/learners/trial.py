"""One trial (episode) of one controller: the hot loop every learner shares.

Every learner spends nearly all its time here, so the loop works on plain Python floats
and lists: with overlapping trapezoids only 2-4 of the M rules fire per state, and numpy's
per-call overhead (and array conversions) on lists that small costs more than the arithmetic.
Everything the loop needs is passed in explicitly, so it can be replaced by a compiled version
without touching the learners. The rule base it evaluates, :class:`SparseRules`, lives in
:mod:`flctool.compile.sparse` (numpy-free, for ``flctool infer`` too) and is re-exported here.

The crisp output is computed with exactly the operations of :meth:`Controller.output` (both
sums accumulated left to right in rule order, then one division), so the controller acts
during learning bit for bit as the deployed one does.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

from flctool.compile.defuzzify import centre_of_area
from flctool.compile.sparse import SparseRules, add_in_order
from flctool.envs.base import BatchEnv

__all__ = ["SparseRules", "Trial", "add_in_order", "run_trial"]


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
              acted: set[int] | None = None, credit: list[float] | None = None) -> Trial:
    """Run one episode from ``seed`` on a batch-of-one ``env``.

    The commands come from the fixed ``consequents (M,)`` (pitt, hybrid) or, step by step, from
    ``chooser`` (fuzzy_q). With ``td``, every step updates the q table (eq. 4-9): trial after
    trial, never summed over simultaneous episodes. A terminal step does not bootstrap; a
    truncated one does (the time limit is not part of the task). ``acted`` collects the rules
    that fired in a state the controller acted on: only their commands shaped the episode.
    ``credit (M,)`` adds up each rule's normalised activation phi_m (eq. 7) over the states
    the controller acted on: how much of the episode each rule's command shaped.
    """
    if chooser is None:
        if consequents is None:
            raise ValueError("run_trial needs consequents or a chooser")
        if td is None and not env.votes:
            return _fixed_trial(env, rules, seed, consequents, acted, credit)
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
        if credit is not None:
            _add_credit(credit, active, alphas, total)
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
                 acted: set[int] | None, credit: list[float] | None) -> Trial:
    """:func:`run_trial` with fixed consequents, no q update and eq. 3 (pitt's trials and
    every validation episode): the same operations with less bookkeeping per step."""
    # each rule's command singleton, so eq. 3 needs no command list
    singleton = [rules.singletons[k] for k in consequents].__getitem__
    clip = rules.clip
    active, alphas, total = rules.activations(env.reset_one(seed).tolist())
    ret = 0.0
    steps = 0
    while True:
        if acted is not None:
            acted.update(active)
        if credit is not None:
            _add_credit(credit, active, alphas, total)
        action = clip(centre_of_area(zip(alphas, map(singleton, active), strict=True), 0.0))
        observation, reward, terminal, truncated = env.step_one(action)
        ret += reward
        steps += 1
        if terminal:
            return Trial(ret, steps, bool(env.success()[0]))
        # a truncated episode's last state is fired too, as run_trial does (its errors count)
        active, alphas, total = rules.activations(observation.tolist())
        if truncated:
            return Trial(ret, steps, bool(env.success()[0]))


def _add_credit(credit: list[float], active: list[int], alphas: list[float],
                total: float) -> None:
    if total <= 0.0:  # no rule fired: no command shaped this step
        return
    for m, alpha in zip(active, alphas, strict=True):
        credit[m] += alpha / total
