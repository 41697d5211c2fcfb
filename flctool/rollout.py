"""Running a controller in an environment: evaluation with confidence intervals, and traces.

Shared by ``flctool evaluate`` and the learners (held-out success). All evaluation episodes
step in lock-step as one batch, so a thousand episodes cost about as many numpy calls as one.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from flctool.compile import Controller
from flctool.envs.base import BatchEnv, BoolArray, FloatArray
from flctool.errors import EnvError

Z95 = 1.959963984540054  # two-sided 95 % quantile of the standard normal

#: Two-sided 95 % quantiles of Student's t by degrees of freedom (n - 1), for the sample sizes
#: runs and evaluations use: 1-30 (selection validates on 20 episodes by default) and the round
#: sizes above (``evaluate`` runs 1,000 by default). The values are ``scipy.special.stdtrit(dof,
#: 0.975)`` of scipy 1.17, so an interval is the same with or without the table; the table
#: spares ``flctool learn`` importing scipy (about 0.17 s of CPU), and keeps results the same
#: across scipy versions.
T975 = {
    1: 12.706204736174694, 2: 4.302652729749462, 3: 3.1824463052837078, 4: 2.7764451051977934,
    5: 2.5705818356363146, 6: 2.4469118511449786, 7: 2.364624251592784, 8: 2.306004135204166,
    9: 2.262157162798205, 10: 2.228138851986274, 11: 2.200985160091639, 12: 2.1788128296672284,
    13: 2.1603686564627913, 14: 2.144786687917804, 15: 2.131449545559776,
    16: 2.1199052992212546, 17: 2.1098155778333156, 18: 2.1009220402410382,
    19: 2.0930240544083087, 20: 2.085963447265864, 21: 2.0796138447276795,
    22: 2.0738730679040254, 23: 2.0686576104190486, 24: 2.0638985616280245,
    25: 2.0595385527532972, 26: 2.0555294386428735, 27: 2.0518305164802846,
    28: 2.0484071417952454, 29: 2.045229642132703, 30: 2.0422724563012378,
    39: 2.022690920036761, 49: 2.0095752371292392, 59: 2.000995378088267,
    99: 1.9842169515864174, 199: 1.9719565442517533, 499: 1.9647293909876886,
    999: 1.9623414611334493,
}


@dataclass(frozen=True)
class Estimate:
    """A mean (or rate) with its 95 % confidence interval [low, high] over n samples.

    With no samples the value is NaN; with one sample a mean has no interval (NaN bounds).
    """

    value: float
    low: float
    high: float
    n: int

    def to_dict(self) -> dict[str, float | int | None]:
        def clean(x: float) -> float | None:
            return None if math.isnan(x) else x
        return {"value": clean(self.value), "low": clean(self.low), "high": clean(self.high),
                "n": self.n}


def wilson_interval(successes: int, n: int) -> Estimate:
    """Success rate with the Wilson score interval (good near 0 and 1, unlike p +- z se)."""
    if n == 0:
        return Estimate(math.nan, math.nan, math.nan, 0)
    p = successes / n
    z2 = Z95 * Z95
    denominator = 1.0 + z2 / n
    centre = (p + z2 / (2 * n)) / denominator
    half = Z95 * math.sqrt(p * (1 - p) / n + z2 / (4 * n * n)) / denominator
    return Estimate(p, max(0.0, centre - half), min(1.0, centre + half), n)


def mean_interval(values: FloatArray) -> Estimate:
    """Mean with Student's t interval (the normal interval for large n, exact for normal data)."""
    data = np.asarray(values, dtype=np.float64)
    n = int(data.shape[0])
    if n == 0:
        return Estimate(math.nan, math.nan, math.nan, 0)
    mean = float(data.mean())
    if n == 1:
        return Estimate(mean, math.nan, math.nan, 1)
    half = t975(n - 1) * float(data.std(ddof=1)) / math.sqrt(n)
    return Estimate(mean, mean - half, mean + half, n)


def clip_estimate(estimate: Estimate, bounds: tuple[float, float]) -> Estimate:
    """``estimate`` with its interval clipped to ``bounds``, the values it can take (a mean
    fitness of 2 at most has no interval above 2)."""
    low, high = bounds
    return Estimate(estimate.value, min(max(estimate.low, low), high),
                    max(min(estimate.high, high), low), estimate.n)


#: From this many degrees of freedom, :func:`t975` takes Cornish-Fisher's expansion of the
#: quantile in 1/dof (Abramowitz & Stegun 26.7.5, four terms): within 2.3e-12 of scipy's
#: value from 200 on, and within 1e-15 from 1,000 (a test compares them), so ``flctool
#: evaluate``, whose steps to success have as many samples as successes, never imports scipy
#: (about 0.2 s of CPU).
T975_EXPANSION_FROM = 200


def _t975_expansion(dof: int) -> float:
    x = Z95
    terms = ((x**3 + x) / 4,
             (5 * x**5 + 16 * x**3 + 3 * x) / 96,
             (3 * x**7 + 19 * x**5 + 17 * x**3 - 15 * x) / 384,
             (79 * x**9 + 776 * x**7 + 1482 * x**5 - 1920 * x**3 - 945 * x) / 92160)
    quantile = x
    for power, g in enumerate(terms, start=1):  # plain additions: the same on every Python
        quantile += g / dof**power
    return quantile


def t975(dof: int) -> float:
    """The 97.5 % quantile of Student's t with ``dof`` degrees of freedom: from :data:`T975`,
    by expansion from :data:`T975_EXPANSION_FROM`, else computed by scipy."""
    quantile = T975.get(dof)
    if quantile is None and dof >= T975_EXPANSION_FROM:
        quantile = _t975_expansion(dof)
    if quantile is None:
        from scipy.special import stdtrit

        quantile = float(stdtrit(dof, 0.975))
    return quantile


@dataclass(frozen=True)
class EvaluationResult:
    """Per-episode outcomes of an evaluation, E episodes, and their summary statistics."""

    seeds: NDArray[np.int64]  # (E,)
    returns: FloatArray  # (E,) undiscounted
    lengths: NDArray[np.int64]  # (E,) steps taken
    success: BoolArray  # (E,)
    fitness: FloatArray  # (E,) the GA's trial fitness (env.episode_fitness)

    @property
    def episodes(self) -> int:
        return int(self.seeds.shape[0])

    @property
    def success_rate(self) -> Estimate:
        return wilson_interval(int(self.success.sum()), self.episodes)

    @property
    def steps_to_success(self) -> Estimate:
        """Mean episode length over the successful episodes only."""
        return mean_interval(self.lengths[self.success].astype(np.float64))

    @property
    def mean_fitness(self) -> Estimate:
        return mean_interval(self.fitness)

    @property
    def mean_return(self) -> Estimate:
        return mean_interval(self.returns)

    def summary(self) -> dict[str, Any]:
        """JSON-ready summary: each statistic as {value, low, high, n} (None for NaN)."""
        return {"episodes": self.episodes,
                "success_rate": self.success_rate.to_dict(),
                "steps_to_success": self.steps_to_success.to_dict(),
                "mean_fitness": self.mean_fitness.to_dict(),
                "mean_return": self.mean_return.to_dict()}


# Episode seeds: four ranges that never meet, so no episode is used for two purposes.
#
#   [0, 2^31 - 1)    flctool evaluate --seed S (and the task suite's held-out episodes)
#   [2^31, 2^32)     a run's confirmation: the fresh figure it reports, and stop.target's
#   [2^32, 2^62)     training trials, from the run's ``env`` stream
#   [2^62, 2^63)     model selection's validation episodes
#
#: ``flctool evaluate``'s seeds lie below this; every seed from it up is one learning uses.
EVALUATION_SEED_HIGH = 2**31 - 1
#: A run's confirmation episodes draw their seeds from [CONFIRMATION_SEED_LOW, TRAIN_SEED_LOW).
CONFIRMATION_SEED_LOW = 2**31
#: Training episodes draw their seeds from [TRAIN_SEED_LOW, TRAIN_SEED_HIGH), above every seed
#: :func:`evaluation_seeds` gives, so an evaluation never replays a training start (model
#: selection's validation seeds lie above, confirmation's below).
TRAIN_SEED_LOW = 2**32
TRAIN_SEED_HIGH = 2**62


def distinct_run_seeds(run_seed: int, stream: int, low: int, high: int,
                       episodes: int) -> NDArray[np.int64]:
    """``episodes`` distinct seeds (E,) in [low, high), drawn from the child ``stream`` of the
    run's seed: the same for the whole run (a resumed run meets the same episodes), and a
    prefix of a longer draw."""
    rng = np.random.default_rng(np.random.SeedSequence(run_seed, spawn_key=(stream,)))
    seeds: list[int] = []
    seen: set[int] = set()
    while len(seeds) < episodes:
        for value in rng.integers(low, high, size=episodes - len(seeds),
                                  dtype=np.int64).tolist():
            if value not in seen:
                seen.add(value)
                seeds.append(value)
    return np.array(seeds, dtype=np.int64)


def evaluation_seeds(seed: int, episodes: int) -> NDArray[np.int64]:
    """``episodes`` distinct episode seeds drawn from ``seed`` (what ``flctool evaluate
    --seed`` uses). Evaluations with different seeds almost surely share no episode (two
    draws of 1,000 from 2^31 - 1 overlap with probability ~5e-4), and never share one with
    training, whose seeds are >= 2^32."""
    if episodes < 1:
        raise EnvError(f"episodes must be at least 1, got {episodes}")
    rng = np.random.default_rng(seed)
    return np.asarray(rng.choice(EVALUATION_SEED_HIGH, size=episodes, replace=False),
                      dtype=np.int64)


def _controller(controller: Controller, consequents: NDArray[np.integer] | None) -> Controller:
    if consequents is not None:
        return controller.with_consequents(np.asarray(consequents, dtype=np.intp))
    controller.require_consequents()  # the controller's one "not deployable" check
    return controller


def evaluate(controller: Controller, env: BatchEnv, seeds: NDArray[np.int64] | list[int],
             consequents: NDArray[np.integer] | None = None) -> EvaluationResult:
    """Run one episode per seed, all in lock-step, with the controller's rules (or the given
    ``consequents (M,)``), and collect their outcomes.

    An adapter that runs at most ``env.max_batch`` episodes at once (a real robot) gets the
    seeds in chunks of that size, one chunk after another.
    """
    flc = _controller(controller, consequents)
    seeds = np.asarray(seeds, dtype=np.int64).reshape(-1)
    if seeds.shape[0] == 0:
        raise EnvError("evaluate needs at least one seed")
    chunk = env.max_batch or seeds.shape[0]
    parts = [_run_lockstep(flc, env, seeds[i : i + chunk])
             for i in range(0, seeds.shape[0], chunk)]
    returns, lengths, success = (np.concatenate(column) for column in zip(*parts, strict=True))
    return EvaluationResult(seeds, returns, lengths, success,
                            env.episode_fitness(returns, lengths, success))


def vote_output(flc: Controller, states: FloatArray) -> FloatArray:
    """The action mode ``vote`` for ``states (B, N)`` -> outputs (B,): each command's firing
    rules sum their activations (eq. 2), the strongest command's singleton is the output;
    ties go to the command listed first.

    Sums run left to right in rule order (a cumulative sum; the inactive rules add exact
    zeros), the same operations as the learners' one-state path, so both agree bit for bit.
    """
    if flc.consequents is None:
        raise EnvError("a vote needs the controller's rule consequents")
    alpha = flc.activations(states)  # (B, M)
    votes = np.zeros((alpha.shape[0], flc.n_commands))
    for k in range(flc.n_commands):
        mine = alpha[:, flc.consequents == k]
        if mine.shape[1]:
            votes[:, k] = np.cumsum(mine, axis=1)[:, -1]
    chosen: FloatArray = flc.singletons[np.argmax(votes, axis=1)]
    return chosen


def _act(flc: Controller, env: BatchEnv, states: FloatArray) -> FloatArray:
    """The actions (B,) for ``states (B, N)``: eq. 3's crisp output, or the vote."""
    return vote_output(flc, states) if env.votes else flc.output(states)


def _run_lockstep(flc: Controller, env: BatchEnv, seeds: NDArray[np.int64],
                  ) -> tuple[FloatArray, NDArray[np.int64], BoolArray]:
    """Returns, lengths and success of one episode per seed, stepped together."""
    count = seeds.shape[0]
    obs, _ = env.reset(seeds)
    returns = np.zeros(count)
    lengths = np.zeros(count, dtype=np.int64)
    done = np.zeros(count, dtype=bool)
    actions = np.zeros(count)
    for _ in range(env.max_steps):
        active = ~done
        # Finished episodes ignore their actions; only the running ones need inference.
        actions[active] = _act(flc, env, obs[active])
        step = env.step(actions)
        returns += np.where(active, step.rewards, 0.0)
        lengths += active
        obs = step.observations
        done = step.terminated | step.truncated
        if done.all():
            break
    else:
        raise EnvError(f"episodes still running after max_steps = {env.max_steps} steps",
                       hint="the adapter must truncate episodes at max_steps")
    return returns, lengths, env.success().copy()


def trace_episode(controller: Controller, env: BatchEnv, seed: int,
                  consequents: NDArray[np.integer] | None = None) -> list[dict[str, Any]]:
    """One episode step by step, as rows for a CSV: step, the adapter's trace state (e.g. robot
    pose, ball), the observations, the crisp output and the command nearest to it. The last
    row is the final state, with no output."""
    flc = _controller(controller, consequents)
    obs, _ = env.reset(np.array([seed], dtype=np.int64))
    rows: list[dict[str, Any]] = []
    for t in range(env.max_steps + 1):
        row: dict[str, Any] = {"step": t}
        row.update({name: float(values[0]) for name, values in env.trace_state().items()})
        row.update({name: float(obs[0, i]) for i, name in enumerate(env.observation_names)})
        if rows and (rows[-1]["terminated"] or rows[-1]["truncated"]):
            row.update({flc.output_name: "", "command": "", "reward": "",
                        "terminated": "", "truncated": ""})
            rows.append(row)
            return rows
        output = float(_act(flc, env, obs)[0])
        nearest = int(np.argmin(np.abs(flc.singletons - output)))
        step = env.step(np.array([output]))
        row.update({flc.output_name: output, "command": flc.command_names[nearest],
                    "reward": float(step.rewards[0]), "terminated": bool(step.terminated[0]),
                    "truncated": bool(step.truncated[0])})
        rows.append(row)
        obs = step.observations
    raise EnvError(f"the episode was still running after max_steps = {env.max_steps} steps",
                   hint="the adapter must truncate episodes at max_steps")
