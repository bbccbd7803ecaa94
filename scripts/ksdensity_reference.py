#!/usr/bin/env python3
"""Reference values of MATLAB R2017a `ksdensity` (default settings, optional 'Support', [L U]).

Writes analysis/tests/fixtures/ksdensity_reference.txt, the fixture that
analysis/tests/stats_kde.rs checks the Rust estimator (analysis/src/kde.rs) against.

This is an independent implementation (numpy, vectorised; it shares no code
with the Rust one), written from MATLAB's documented algorithm:
  * Gaussian kernel;
  * 'Support', [L U]: data mapped by t = log(y - L) - log(U - y); the estimate
    is made in t and mapped back with the Jacobian dt/dy = (U - L)/((y - L)(U - y));
    the bandwidth is reported and computed on the t scale;
  * bandwidth: sigma = median(|t - median(t)|) / 0.6745, h = sigma (4/(3n))^(1/5)
    ("optimal for normal densities", Bowman & Azzalini 1997); sigma falls back to
    max(t) - min(t) when the MAD is 0, and h = 1 when that is 0 too;
  * default evaluation points: NumPoints (100) equally spaced points in y from
    y(min(t) - 3h) to y(max(t) + 3h), y() the inverse transform;
  * for n * NumPoints > 30000 kernel evaluations MATLAB sums, per evaluation
    point x (in t), only over the sorted data from the first t_i >= x - 4h to
    the first t_i > x + 4h inclusive (normal kernel cutoff 4).
The last three points are the behaviour of MATLAB's statkscompute.m
(compute_default_xi, dokernel), which the documentation summarises as "100
equally spaced points that cover the range of the data".

Optionally (--octave DIR) every case is also run through GNU Octave's
statistics package `ksdensity` (DIR = a checkout's inst/Descriptive_Statistics,
e.g. github.com/gnu-octave/statistics at c2e3c2b6, 2026-08-23; it runs under
Octave 7.3 when DIR is put on the path together with its private/ folder).
Octave implements the same estimator except (a) its default grid is equally
spaced in t, not y (only its end points agree with MATLAB), (b) it never
truncates the kernel sum, (c) its MAD = 0 fallback is std(t), not the range.
So Octave is evaluated at our grid, and only cases without (b), (c) are stored
as Octave values in the fixture.

Usage: python3 scripts/ksdensity_reference.py [--octave DIR] [--out FILE]
"""

import argparse
import os
import subprocess
import sys
import tempfile

import numpy as np

BLOCK_SIZE = 30000  # MATLAB's threshold on n * m for the full kernel sum
CUTOFF = 4.0  # normal kernel cutoff (bandwidths) in the truncated sum
MARGIN = 3.0  # default grid margin beyond the data (bandwidths, in t)


def forward(y, support):
    if support is None:
        return np.asarray(y, dtype=float)
    lo, hi = support
    y = np.asarray(y, dtype=float)
    return np.log(y - lo) - np.log(hi - y)


def inverse(t, support):
    if support is None:
        return t
    lo, hi = support
    t = float(t)
    if t < 0:
        e = np.exp(t)
        return (hi * e + lo) / (e + 1.0)
    e = np.exp(-t)
    return (hi + lo * e) / (1.0 + e)


def jacobian(y, support):
    if support is None:
        return np.ones_like(y)
    lo, hi = support
    return (hi - lo) / ((y - lo) * (hi - y))


def bandwidth(t):
    n = t.size
    sigma = np.median(np.abs(t - np.median(t))) / 0.6745
    if sigma <= 0:
        sigma = t.max() - t.min()
    if sigma > 0:
        return sigma * (4.0 / (3.0 * n)) ** 0.2
    return 1.0


def matlab_linspace(a, b, n):
    if n == 1:
        return np.array([b])
    v = a + np.arange(n) * ((b - a) / (n - 1))
    v[-1] = b
    return v


def density(sample, support, points):
    """MATLAB ksdensity(sample, points, 'Support', support) and its bandwidth."""
    t = forward(sample, support)
    h = bandwidth(t)
    points = np.asarray(points, dtype=float)
    out = np.zeros(points.size)
    if support is None:
        inside = np.isfinite(points)
    else:
        inside = (points > support[0]) & (points < support[1])
    x = forward(points[inside], support)
    n = t.size
    if n * points.size <= BLOCK_SIZE:
        z = (x[:, None] - t[None, :]) / h
        k = np.exp(-0.5 * z**2) / np.sqrt(2 * np.pi)
        f = k.sum(axis=1) / n
    else:
        ts = np.sort(t)
        f = np.empty(x.size)
        for j, xj in enumerate(x):
            start = min(np.searchsorted(ts, xj - CUTOFF * h, side="left"), n - 1)
            end = max(min(np.searchsorted(ts, xj + CUTOFF * h, side="right"), n - 1), start)
            z = (xj - ts[start : end + 1]) / h
            f[j] = (np.exp(-0.5 * z**2) / np.sqrt(2 * np.pi)).sum() / n
    out[inside] = f * jacobian(points[inside], support) / h
    return out, h


def default_grid(sample, support, m=100):
    t = forward(sample, support)
    h = bandwidth(t)
    return matlab_linspace(inverse(t.min() - MARGIN * h, support), inverse(t.max() + MARGIN * h, support), m)


def cases():
    """Samples: fixed by hand or drawn from a seeded generator (values are stored, so the seed only documents them)."""
    rng = np.random.default_rng(2017)
    out = []
    out.append(("hand7", np.array([-3.1, -1.0, 0.2, 0.5, 1.7, 2.2, 4.9]), (-6.0, 6.0), None))
    side = np.where(rng.random(60) < 0.5, -1.0, 1.0)
    out.append(("slippers60", np.clip(side * 2.5 + rng.normal(0, 0.6, 60), -5.9, 5.9), (-6.0, 6.0), None))
    out.append(("centred150", np.clip(rng.normal(0.0, 0.8, 150), -5.9, 5.9), (-6.0, 6.0), None))
    mix = np.concatenate([rng.normal(0.0, 0.6, 250), rng.normal(3.0, 0.7, 150)])
    out.append(("large400", np.clip(mix, -5.95, 5.95), (-6.0, 6.0), None))  # n*m = 40000 > 30000: truncated sum
    out.append(("near_walls12", np.array([-5.99, -5.9, -5.5, -4.0, -1.0, 0.0, 0.3, 2.0, 4.4, 5.5, 5.8, 5.995]), (-6.0, 6.0), None))
    out.append(("unbounded50", rng.normal(1.0, 2.0, 50), None, None))
    out.append(("mad_zero7", np.array([1.0, 1.0, 1.0, 1.0, 2.0, 3.5, -2.0]), (-6.0, 6.0), None))
    out.append(("other_support9", rng.uniform(0.5, 9.5, 9), (0.0, 10.0), None))
    pts = np.array([-7.0, -6.0, -5.999, -3.0, -0.25, 0.0, 1.0, 5.5, 6.0, 6.5])
    out.append(("given_points", np.array([-2.0, -0.5, 0.0, 0.4, 1.1, 3.0]), (-6.0, 6.0), pts))
    return out


def octave_density(octave_dir, sample, support, points):
    """Octave's ksdensity at `points`, its bandwidth, and its own default grid (100 points)."""
    with tempfile.TemporaryDirectory() as tmp:
        np.savetxt(os.path.join(tmp, "x.txt"), sample, fmt="%.17g")
        np.savetxt(os.path.join(tmp, "p.txt"), points, fmt="%.17g")
        sup = "" if support is None else f", 'Support', [{support[0]!r} {support[1]!r}]"
        script = (
            f"addpath('{octave_dir}'); x = load('{tmp}/x.txt'); p = load('{tmp}/p.txt');"
            f"[f, xi, bw] = ksdensity(x, p{sup}); [g, gi] = ksdensity(x{sup});"
            f"fid = fopen('{tmp}/o.txt', 'w'); fprintf(fid, '%.17g\\n', bw, gi(1), gi(end), f); fclose(fid);"
        )
        subprocess.run(["octave", "--no-gui", "--quiet", "--eval", script], check=True, capture_output=True)
        v = np.loadtxt(os.path.join(tmp, "o.txt"))
    return v[3:], v[0], (v[1], v[2])


def fmt(v):
    return " ".join(f"{x:.17g}" for x in v)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--octave", help="directory with the Octave statistics package's ksdensity.m (and private/)")
    ap.add_argument("--out", default=os.path.join(os.path.dirname(__file__), "..", "analysis", "tests", "fixtures", "ksdensity_reference.txt"))
    args = ap.parse_args()

    lines = [
        "# MATLAB R2017a ksdensity reference values; generated by scripts/ksdensity_reference.py (numpy "
        + np.__version__
        + ("" if not args.octave else ", cross-checked with GNU Octave statistics ksdensity")
        + ").",
        "# One block per case: 'case NAME', 'support L U' or 'support none', 'sample ...', 'bandwidth h',",
        "# 'y ...' (MATLAB's default 100-point grid, or the given points), 'density ...',",
        "# optionally 'octave_bandwidth h' and 'octave_density ...' (Octave at the same y), 'end'.",
    ]
    worst = 0.0
    for name, sample, support, points in cases():
        grid = default_grid(sample, support) if points is None else points
        f, h = density(sample, support, grid)
        lines.append(f"case {name}")
        lines.append("support none" if support is None else f"support {support[0]!r} {support[1]!r}")
        lines.append("sample " + fmt(sample))
        lines.append(f"bandwidth {h:.17g}")
        lines.append("y " + fmt(grid))
        lines.append("density " + fmt(f))
        if args.octave:
            # Octave takes logs of points outside the support (complex values): ask only inside,
            # and keep MATLAB's 0 outside
            inside = np.ones(grid.size, bool) if support is None else (grid > support[0]) & (grid < support[1])
            fo_in, ho, (g0, g1) = octave_density(args.octave, sample, support, grid[inside])
            fo = np.zeros(grid.size)
            fo[inside] = fo_in
            dev = np.max(np.abs(fo - f))
            rel = np.max(np.abs(fo - f) / np.maximum(np.abs(f), 1e-300))
            ends = max(abs(g0 - grid[0]), abs(g1 - grid[-1])) if points is None else 0.0
            print(f"{name:15s} n={sample.size:4d} h={h:.6f} octave: |dh|={abs(ho - h):.2e} max|df|={dev:.2e} max rel={rel:.2e} grid ends {ends:.2e}", file=sys.stderr)
            comparable = name not in ("large400", "mad_zero7")
            if comparable:
                worst = max(worst, dev, abs(ho - h), ends)
                lines.append(f"octave_bandwidth {ho:.17g}")
                lines.append("octave_density " + fmt(fo))
        lines.append("end")
    if args.octave:
        print(f"max deviation numpy vs Octave over comparable cases: {worst:.3e}", file=sys.stderr)
    with open(args.out, "w") as fh:
        fh.write("\n".join(lines) + "\n")
    print(f"wrote {args.out}", file=sys.stderr)


if __name__ == "__main__":
    main()
