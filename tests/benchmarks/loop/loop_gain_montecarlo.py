#!/usr/bin/env python3
"""How much lower can one loop closure make the ATE?  (doc/evaluation.md "Batch")

Monte Carlo on a planar SE(2) pose graph: a camera drives a circle of N steps; odometry
measures each step with an error; one loop constraint (start = end, 10x more precise than a
step) closes it. The closed estimate is the maximum-likelihood pose graph solution (Gauss-
Newton via scipy's least_squares); both it and dead reckoning are scored by ATE RMSE after
rigid (SE(2)) alignment, the way keygrid-eval scores trajectories. Printed: the ratio
ATE(open) / ATE(closed) over the trials, per kind of odometry error:

* independent translation errors (a random walk of the position): the closed estimate is a
  bridge of that walk, and the expected ratio is ~sqrt(3) before alignment;
* independent heading errors (a random walk of the heading, integrated into position);
* a constant heading bias (systematic drift, e.g. a depth distortion bending the path).

Usage: python3 tests/benchmarks/loop/loop_gain_montecarlo.py [TRIALS=100]   (numpy, scipy)
"""
import sys

import numpy as np
from scipy.optimize import least_squares
from scipy.sparse import lil_matrix


def compose(a, b):
    c, s = np.cos(a[2]), np.sin(a[2])
    return np.array([a[0] + c * b[0] - s * b[1], a[1] + s * b[0] + c * b[1], a[2] + b[2]])


def between(a, b):
    """Pose of b in the frame of a."""
    c, s = np.cos(a[2]), np.sin(a[2])
    d = b[:2] - a[:2]
    return np.array([c * d[0] + s * d[1], -s * d[0] + c * d[1], np.arctan2(np.sin(b[2] - a[2]), np.cos(b[2] - a[2]))])


def ate(est, gt):
    """RMSE of the positions after the best rigid alignment (Horn / Umeyama, no scale)."""
    x, y = est[:, :2], gt[:, :2]
    mx, my = x.mean(0), y.mean(0)
    u, _, vt = np.linalg.svd((y - my).T @ (x - mx))
    d = np.diag([1.0, np.sign(np.linalg.det(u @ vt))])
    z = ((u @ d @ vt) @ (x - mx).T).T + my
    return np.sqrt(((z - y) ** 2).sum(1).mean())


def trial(rng, n, sigma_t, sigma_r, bias_r):
    th = np.linspace(0, 2 * np.pi, n + 1)[:-1]
    gt = np.stack([5 * np.cos(th), 5 * np.sin(th), th + np.pi / 2], 1)  # 31 m circle
    odo = [between(gt[i], gt[i + 1]) + rng.normal(0, 1, 3) * [sigma_t, sigma_t, sigma_r] + [0, 0, bias_r]
           for i in range(n - 1)]
    loop = between(gt[n - 1], gt[0])
    dead = [gt[0]]
    for o in odo:
        dead.append(compose(dead[-1], o))
    dead = np.array(dead)
    # step information: the noise the optimiser assumes (a bias looks like noise to it)
    w = np.array([1 / max(sigma_t, 1e-3)] * 2 + [1 / max(sigma_r, bias_r, 1e-4)])

    def wrap(e):
        e[2] = np.arctan2(np.sin(e[2]), np.cos(e[2]))
        return e

    def residuals(x):
        p = np.vstack([gt[0], x.reshape(-1, 3)])  # first pose fixed: the gauge
        r = [wrap(between(p[i], p[i + 1]) - o) * w for i, o in enumerate(odo)]
        r.append(wrap(between(p[n - 1], p[0]) - loop) * w * 10)
        return np.concatenate(r)

    # residual block i (step i -> i+1) depends on poses i and i+1; pose 0 is not a variable
    sparsity = lil_matrix((3 * n, 3 * (n - 1)), dtype=int)
    for i in range(n - 1):
        for p in (i - 1, i):
            if p >= 0:
                sparsity[3 * i:3 * i + 3, 3 * p:3 * p + 3] = 1
    sparsity[3 * (n - 1):, 3 * (n - 2):] = 1
    sol = least_squares(residuals, dead[1:].ravel(), jac_sparsity=sparsity, x_scale="jac")
    closed = np.vstack([gt[0], sol.x.reshape(-1, 3)])
    return ate(dead, gt) / ate(closed, gt)


def main():
    trials = int(sys.argv[1]) if len(sys.argv) > 1 else 100
    rng = np.random.default_rng(1)
    cases = [("translation noise 1 cm / step", 0.01, 0.0, 0.0),
             ("heading noise 0.1 deg / step", 0.0, np.radians(0.1), 0.0),
             ("both", 0.01, np.radians(0.1), 0.0),
             ("heading bias 0.05 deg / step + translation noise", 0.01, 0.0, np.radians(0.05))]
    print("ATE(open) / ATE(closed) for one loop closure, %d trials, 100 steps of 0.31 m" % trials)
    for label, st, sr, br in cases:
        r = np.array([trial(rng, 100, st, sr, br) for _ in range(trials)])
        print("  %-50s median %.2f, 10-90 %%: %.2f-%.2f, share >= 3x: %3.0f %%" % (
            label, np.median(r), *np.percentile(r, [10, 90]), 100 * (r >= 3).mean()))


if __name__ == "__main__":
    main()
