#!/usr/bin/env python3
"""Independent 60-digit check of placed closed loops (needs mpmath).

Each file (written by crates/quell/tests/place.rs with QUELL_DUMP_DIR set) holds M = A - BK row by
row in exact decimal form and, on its last line, '# re,im re,im ...', the requested poles. Prints
the largest |lambda - p| / max(1, |p|) over the poles, each matched to the nearest unmatched
eigenvalue of M computed with 60 significant digits. Usage:

    mkdir -p /tmp/m && QUELL_DUMP_DIR=/tmp/m cargo test -p quell --release --test place
    python3 scripts/mp_eigenvalues.py /tmp/m/*.txt
"""

import sys

import mpmath

mpmath.mp.dps = 60
worst_all = 0.0
for path in sys.argv[1:]:
    lines = open(path).read().split("\n")
    # float(x) first: the decimal string names a double, which mpf must take exactly.
    rows = [[mpmath.mpf(float(x)) for x in l.split()] for l in lines if l.strip() and not l.startswith("#")]
    poles = [complex(float(a), float(b)) for a, b in (t.split(",") for t in lines[-1][2:].split())]
    free = list(mpmath.eig(mpmath.matrix(rows), left=False, right=False))
    worst = 0.0
    for p in poles:
        j = min(range(len(free)), key=lambda j: abs(free[j] - p))
        worst = max(worst, float(abs(free.pop(j) - p)) / max(1.0, abs(p)))
    worst_all = max(worst_all, worst)
    print(f"{path}: {worst:.3e}")
print(f"{len(sys.argv) - 1} files, largest error {worst_all:.3e}")
