"""A scripted spiral search and its improvement by a small cross-entropy search, in one command.

    python -m compliant_docking.env.example                 # a few minutes on 2 cores
    python -m compliant_docking.env.example --quick         # a smoke test (seconds of work)
    python -m compliant_docking.env.example --record-dir runs/env_example   # test episodes as runs

The socket is misaligned laterally by up to ±16 mm on each axis (``--misalignment``),
beyond the funnel's capture (about 11 mm): the planner alone docks only the draws inside
it. The spiral search (:mod:`compliant_docking.env.policies`) finds the funnel from where
the plug lands on the socket; the cross-entropy method then tunes its parameters on
training draws, maximising the mean episode return (the environment's reward: its success
bonus, shaping and force penalty). The three policies are compared on the same held-out
draws (common random numbers: test seeds 0 … n−1, training seeds from 10 000 on): success
rates with Wilson 95 % intervals, and McNemar's exact test on the paired outcomes.
Episodes run on ``--workers`` processes (default: every core), one environment each.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass

import numpy as np

from compliant_docking.env.policies import PlainPlanner, SpiralParams, SpiralSearch

#: the first training seed (test seeds start at 0: the two sets never meet)
TRAIN_SEED = 10_000

_env = None  # the worker's environment (one per process)


def _start_worker(overrides: list[str]) -> None:
    global _env
    from compliant_docking.env import make_env

    _env = make_env(*overrides)


def episode(job: tuple[str, tuple[float, ...] | None, int]) -> tuple[bool, float]:
    """(success, return) of one episode: ``job`` = (policy name, spiral parameters, seed)."""
    name, params, seed = job
    env = _env
    assert env is not None
    if name == "plain":
        policy: PlainPlanner | SpiralSearch = PlainPlanner(env.action_mode.size)
    else:
        settings = env.settings
        policy = SpiralSearch(
            SpiralParams.from_vector(params), env.names, settings.action.max_offset_m, settings.policy_step
        )
    obs, _ = env.reset(seed=seed)
    policy.reset()
    total = 0.0
    while True:
        obs, reward, terminated, truncated, info = env.step(policy(obs))
        total += reward
        if terminated or truncated:
            return bool(info["is_success"]), total


@dataclass
class Outcome:
    name: str
    success: np.ndarray  # per test seed
    returns: np.ndarray


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--test", type=int, default=24, help="held-out draws per policy")
    parser.add_argument("--train", type=int, default=6, help="training draws per candidate")
    parser.add_argument("--iterations", type=int, default=3, help="cross-entropy iterations")
    parser.add_argument("--population", type=int, default=6, help="candidates per iteration")
    parser.add_argument("--elite", type=int, default=3, help="candidates kept per iteration")
    parser.add_argument("--misalignment", type=float, default=0.016, help="lateral bound per axis [m]")
    parser.add_argument("--workers", type=int, default=os.cpu_count() or 1)
    parser.add_argument("--record-dir", default=None, help="write the test episodes as run directories here")
    parser.add_argument("--quick", action="store_true", help="a smoke test: tiny sets, one iteration")
    parser.add_argument("overrides", nargs="*", help="more overrides of the run and the env (env.*)")
    args = parser.parse_args(argv)
    if args.quick:
        args.test, args.train, args.iterations, args.population, args.elite = 2, 1, 1, 2, 1
    m = args.misalignment
    overrides = [
        f"task.misalignment.x_range=[{-m},{m}]",
        f"task.misalignment.y_range=[{-m},{m}]",
        "task.progress=false",
        *args.overrides,
    ]
    started = time.perf_counter()
    print(f"load {_load()}; {args.workers} worker(s); overrides: {' '.join(overrides)}")
    train_pool = ProcessPoolExecutor(args.workers, initializer=_start_worker, initargs=(overrides,))
    test_overrides = [*overrides, f"env.record_dir={args.record_dir}"] if args.record_dir else overrides
    test_pool = ProcessPoolExecutor(args.workers, initializer=_start_worker, initargs=(test_overrides,))
    with train_pool, test_pool:
        hand = SpiralParams()
        tuned = cross_entropy(train_pool, hand, args)
        outcomes = [
            evaluate(test_pool, "plain planner", "plain", None, args.test),
            evaluate(test_pool, "spiral search (hand-set)", "spiral", hand.vector(), args.test),
            evaluate(test_pool, "spiral search (tuned)", "spiral", tuned.vector(), args.test),
        ]
    report(outcomes, tuned)
    print(f"\n{time.perf_counter() - started:.0f} s wall; load {_load()}")
    return 0


def cross_entropy(pool: ProcessPoolExecutor, start: SpiralParams, args) -> SpiralParams:
    """The cross-entropy method on the spiral's parameters, in the box of their bounds:
    a diagonal Gaussian around ``start`` (σ a quarter of each range), refitted to the elite
    each iteration; the score is the mean return over the same training draws."""
    low, high = SpiralParams.bounds()
    mean, std = start.vector(), (high - low) / 4.0
    rng = np.random.default_rng(0)
    seeds = [TRAIN_SEED + i for i in range(args.train)]
    best, best_score = start.vector(), _score(pool, start.vector(), seeds)
    print(f"\ncross-entropy search ({args.iterations} × {args.population} candidates × {args.train} draws)")
    print(f"  start: mean return {best_score:7.2f}")
    for iteration in range(args.iterations):
        candidates = np.clip(rng.normal(mean, std, size=(args.population, len(mean))), low, high)
        scores = np.array([_score(pool, c, seeds) for c in candidates])
        elite = candidates[np.argsort(scores)[::-1][: args.elite]]
        mean, std = elite.mean(axis=0), np.maximum(elite.std(axis=0), (high - low) / 50.0)
        if scores.max() > best_score:
            best, best_score = candidates[int(np.argmax(scores))], float(scores.max())
        print(
            f"  iteration {iteration + 1}: mean return best {scores.max():7.2f}, "
            f"median {np.median(scores):7.2f}; best so far {best_score:7.2f}"
        )
    return SpiralParams.from_vector(best)


def _score(pool: ProcessPoolExecutor, params: np.ndarray, seeds: list[int]) -> float:
    results = list(pool.map(episode, [("spiral", tuple(params), s) for s in seeds]))
    return float(np.mean([r for _, r in results]))


def evaluate(pool: ProcessPoolExecutor, label: str, name: str, params, n: int) -> Outcome:
    jobs = [(name, None if params is None else tuple(params), seed) for seed in range(n)]
    results = list(pool.map(episode, jobs))
    return Outcome(label, np.array([s for s, _ in results]), np.array([r for _, r in results]))


def report(outcomes: list[Outcome], tuned: SpiralParams) -> None:
    from compliant_docking.results.stats import mcnemar, wilson

    n = len(outcomes[0].success)
    print(f"\nsuccess on the same {n} held-out misaligned draws (test seeds 0 … {n - 1}):")
    print(f"  {'policy':28s} {'success':>9s}   {'95 % interval':>15s}   {'mean return':>11s}")
    for o in outcomes:
        k = int(o.success.sum())
        lo, hi = wilson(k, n)
        print(f"  {o.name:28s} {k:3d} / {n:<3d}   [{lo:5.2f}, {hi:5.2f}]   {o.returns.mean():11.2f}")
    plain, hand, tuned_outcome = outcomes
    print("\npaired on the draws (McNemar's exact test):")
    for a, b in ((plain, hand), (plain, tuned_outcome), (hand, tuned_outcome)):
        only_a, only_b, p = mcnemar(a.success, b.success)
        print(f"  {b.name} vs {a.name}: {only_b} draws only it docks, {only_a} only the other; p = {p:.3g}")
    print("\ntuned parameters:")
    for key, value in vars(tuned).items():
        print(f"  {key:20s} {value:.4g}")


def _load() -> str:
    try:
        with open("/proc/loadavg") as f:
            return " ".join(f.read().split()[:3])
    except OSError:
        return "n/a"


if __name__ == "__main__":
    sys.exit(main())
