"""Reference values for the stats crate (run with SciPy 1.17.1).

Prints the fixture arrays (as Rust consts) and, for every test case, the
SciPy call and its result. The Rust tests hold these values literally; this
script documents where they came from and regenerates them:

    pip install scipy==1.17.1
    python3 stats/scripts/scipy_reference.py fixtures \
        > stats/src/fixtures.rs && cargo fmt -p stats
    python3 stats/scripts/scipy_reference.py cases
"""

import sys
import warnings

import numpy as np
import scipy
from scipy import special, stats


def steps(rng, n, fail_rate):
    """Episode lengths: integers in [5, 1000), failures recorded as 1000."""
    s = rng.integers(5, 1000, size=n).astype(float)
    s[rng.random(n) < fail_rate] = 1000.0
    return s


def fixtures():
    rng = np.random.default_rng(20240501)
    fx = {}
    # Paired agents on the same 200 seeds: B is a bit better, both often fail
    # (zero differences at 1000), and integer steps give many ties in |d|.
    a = steps(rng, 200, 0.35)
    b = a.copy()
    redo = rng.random(200) < 0.6
    b[redo] = steps(rng, int(redo.sum()), 0.25)
    fx["PAIRED_A"], fx["PAIRED_B"] = a, b
    # Two independent agents for Mann-Whitney and KS.
    fx["STEPS_200"] = steps(rng, 200, 0.40)
    fx["STEPS_250"] = steps(rng, 250, 0.25)
    fx["STEPS_300"] = steps(rng, 300, 0.30)
    fx["STEPS_500_A"] = steps(rng, 500, 0.30)
    fx["STEPS_500_B"] = steps(rng, 500, 0.20)
    # 8 against 300 with no ties at all (exact Mann-Whitney), and with ties.
    pool = rng.permutation(np.arange(5, 2000))[:308].astype(float) / 2
    fx["DISTINCT_8"], fx["DISTINCT_300"] = pool[:8], pool[8:]
    fx["STEPS_8"] = steps(rng, 8, 0.3)
    # n = 60 paired, no ties, no zeros (asymptotic because n > 50).
    d = rng.permutation(np.arange(1, 61)) * np.where(rng.random(60) < 0.35, -1, 1)
    fx["D_60"] = d.astype(float)
    return fx


def rust_array(name, values):
    vals = ", ".join(repr(float(v)) for v in values)
    return f"pub(super) const {name}: [f64; {len(values)}] = [{vals}];"


def big_x():
    # Formula data (same in ks.rs tests): i * 7919 + 13 mod 10007.
    return np.array([float((i * 7919 + 13) % 10007) for i in range(12000)])


def big_y(n, scale):
    return np.array([float((i * 104729 + 7) % 9973) * scale for i in range(n)])


def near_y(n, offset, scale):
    # Formula data (same in ks.rs tests): like big_x, shifted and scaled.
    return np.array([float(((i + offset) * 7919 + 13) % 10007) * scale for i in range(n)])


def show(call, res):
    print(f"{call}\n    -> {res!r}")


def cases():
    fx = fixtures()
    g = dict(fx)
    print("scipy", scipy.__version__, "numpy", np.__version__)
    wil = [
        ("[125,115,130,140,141,115,140,125,140,135]", "[110,122,125,120,140,124,123,137,134,145]"),
        ("[110,122,125,120,140,124,123,137,134,145]", "[125,115,130,140,141,115,140,125,140,135]"),
        ("np.arange(1, 21) * [1,1,1,-1,1,1,1,1,1,1,1,1,-1,1,1,1,1,1,1,1]", None),
        ("np.arange(1, 51) * np.where(np.arange(1, 51) % 7 == 0, -1, 1)", None),
        ("np.arange(1, 52) * np.where(np.arange(1, 52) % 7 == 0, -1, 1)", None),
        ("[3, -1, 4, 1, -5, 9, 2, 6, 5, 3]", None),
        ("[1, 2, 3, 4, 5, 6, 7, 8]", "[0, 2, 1, 4, 7, 3, 4, 1]"),
        ("[0, 0, 2, -2, 3, 3, 5, 6, 7, -8, 9, 10, 11]", None),
        ("[0, 0, 2, -2, 3, 3, 5, 6, 7, -8, 9, 10, 11, 12]", None),
        ("[0, 1, -1, 2, 2, -3, 4, 4, 4, 5, -5, 6, 0, 7, 8, 8, -9, 10, 11, 12, 0, 13, 14, -14, 15, 16, 17, 17, 18, 19]", None),
        ("D_60", None),
        ("PAIRED_A", "PAIRED_B"),
        ("[0, 0, 0, 0, 0]", None),
        ("np.zeros(20)", None),
        ("[-0.5]", None),
        ("[0.0, -0.0, 1.0, 2.0, -3.0]", None),
    ]
    for x, y in wil:
        for corr in (False, True):
            xv = eval(x, {"np": np, **g})
            args = f"{x}, {y}" if y else x
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                if y:
                    r = stats.wilcoxon(np.asarray(xv, float), np.asarray(eval(y, {"np": np, **g}), float), correction=corr)
                else:
                    r = stats.wilcoxon(np.asarray(xv, float), correction=corr)
            show(f"scipy.stats.wilcoxon({args}, correction={corr})", r)

    mwu = [
        ("[19, 22, 16, 29, 24]", "[20, 11, 17, 12]"),
        ("[20, 11, 17, 12]", "[19, 22, 16, 29, 24]"),
        ("DISTINCT_8", "DISTINCT_300"),
        ("DISTINCT_300", "DISTINCT_8"),
        ("[1.5, 7.25, 3.0]", "[2.0, 4.0, 5.0, 6.0, 8.0, 9.0, 10.0, 11.0, 12.0]"),
        ("[1, 2, 3, 4, 5]", "[6, 7, 8, 9, 10]"),
        ("[1, 2, 2, 3]", "[2, 3, 4]"),
        ("[1, 3, 5, 7, 9, 11, 13, 15, 17]", "[2, 4, 6, 8, 10, 12, 14, 16, 18, 20, 22, 24]"),
        ("STEPS_8", "STEPS_300"),
        ("STEPS_200", "STEPS_250"),
        ("STEPS_500_A", "STEPS_500_B"),
        ("[7.0] * 30", "[7.0] * 40"),
        ("[1.0]", "[2.0]"),
    ]
    for x, y in mwu:
        xv = np.asarray(eval(x, {"np": np, **g}), float)
        yv = np.asarray(eval(y, {"np": np, **g}), float)
        show(f"scipy.stats.mannwhitneyu({x}, {y})", stats.mannwhitneyu(xv, yv))
    # 8 against 20000, no ties: exact (formula data, see mann_whitney.rs).
    yv = np.arange(20000) * 0.5
    xv = np.array([10.25, 100.25, 1000.25, 2000.25, 3000.25, 5000.25, 7000.25, 9990.25])
    show("scipy.stats.mannwhitneyu(X8, np.arange(20000) * 0.5)", stats.mannwhitneyu(xv, yv))

    ks = [
        ("[0.61, 0.29, 0.06, 0.59, -1.73, -0.74, 0.51, -0.56, 0.39, 1.64]", "[-0.1, 1.2, 0.81, 1.5, 0.3, 2.1, 0.95, 0.71, 1.33, 0.02]"),
        ("[0.61, 0.29, 0.06, 0.59, -1.73, -0.74, 0.51, -0.56]", "[-0.1, 1.2, 0.81, 1.5, 0.3, 2.1, 0.95, 0.71, 1.33, 0.02, 1.7]"),
        ("[1, 2, 2, 3, 3, 3, 4]", "[2, 3, 3, 4, 4, 5, 5, 5, 6]"),
        ("[1000.0] * 500", "[1000.0] * 500"),
        ("[1.0]", "[2.0]"),
        ("STEPS_200", "STEPS_300"),
        ("STEPS_500_A", "STEPS_500_B"),
        ("STEPS_8", "STEPS_300"),
    ]
    for x, y in ks:
        xv = np.asarray(eval(x, {"np": np, **g}), float)
        yv = np.asarray(eval(y, {"np": np, **g}), float)
        r = stats.ks_2samp(xv, yv)
        show(f"scipy.stats.ks_2samp({x}, {y})", (float(r.statistic), float(r.pvalue)))
    # Asymptotic (max(n1, n2) > 10000), formula data, see ks.rs tests.
    for (nx, ny, scale) in [(12000, 50, 1.0), (12000, 50, 1.2), (12000, 11000, 1.0), (12000, 11000, 1.01), (10001, 10000, 1.0), (12000, 300, 1.1)]:
        xv = big_x()[:nx]
        yv = big_y(ny, scale)
        r = stats.ks_2samp(xv, yv)
        m, n = max(nx, ny), min(nx, ny)
        show(f"scipy.stats.ks_2samp(big_x({nx}), big_y({ny}, {scale}))  # en={np.round(m*n/(m+n))}",
             (float(r.statistic), float(r.pvalue)))

    for (ny, off, scale) in [(50, 1000, 1.1), (50, 0, 1.3), (100, 0, 1.1)]:
        xv = big_x()
        yv = near_y(ny, off, scale)
        r = stats.ks_2samp(xv, yv)
        en = np.round(12000 * ny / (12000 + ny))
        show(f"scipy.stats.ks_2samp(big_x(12000), near_y({ny}, {off}, {scale}))  # en={en}",
             (float(r.statistic), float(r.pvalue)))
    print("kstwo.sf")
    for n, x in [(5, 0.15), (3, 0.3), (200, 0.004), (10, 0.95), (10, 0.6), (100, 0.05), (100, 0.15),
                 (100, 0.3), (1000, 0.06), (1000, 0.01), (1000, 0.03), (200000, 0.002),
                 (2000000, 0.002), (1000, 0.7), (50, 0.001), (140, 0.0716), (5739, 0.015),
                 (5739, 0.0196), (300, 0.1)]:
        print(f"    ({n}.0, {x!r}, {float(stats.kstwo.sf(x, n))!r}),")
    print("smirnov")
    for n, x in [(1, 0.3), (2, 0.75), (5, 0.1), (10, 0.6), (100, 0.3), (1000, 0.06), (5000, 0.03),
                 (2000000, 0.002), (20, 0.05), (30, 0.5)]:
        print(f"    ({n}, {x!r}, {float(special.smirnov(n, x))!r}),")


if __name__ == "__main__":
    if sys.argv[1:] == ["fixtures"]:
        print("//! Test data generated by stats/scripts/scipy_reference.py.\n")
        for name, values in fixtures().items():
            print(rust_array(name, values))
    else:
        cases()
