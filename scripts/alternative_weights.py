#!/usr/bin/env python3
"""Measures what predicts a wrong bearing and fits the weights of the alternative directions.

  build/bin/bearing-accuracy --rooms 60 --stream --development --snr 25 --algo default \\
      --algo aoa_only --algo music --dump DUMP.csv
  python3 scripts/alternative_weights.py DUMP.csv [--threshold-deg 15]

DUMP.csv has one row per bearing with the folded error of the chosen direction and, in the
`candidates` cell, every other direction the estimator weighed ("error:weight:relative_power:
delay_after_ns:kept;..."). A candidate is "the right one" when the chosen direction is beyond the
threshold and the candidate within it. Prints:
  1. P(chosen wrong, > 30°) binned by the strongest candidate's relative power and the chosen
     direction's quality (what predicts error);
  2. a logistic fit of P(candidate right | ln relative power, 1 − quality, has delay, delay
     after the chosen path [ns]) by Newton's method (no numpy), its coefficients for
     BearingMath.cpp, and its calibration (predicted vs observed by decile);
  3. per estimator, the share of central bearings beyond 30° and beyond 30° from all of the
     alternatives the fitted weights would keep (weight ≥ 0.01 or stronger than the chosen
     direction, at most 3).
"""
import argparse
import csv
import math
import sys

MIN_WEIGHT, MAX_ALTS = 0.01, 3


def features(rho, delay_ns, quality):
    """As alternativeWeight() computes them."""
    has_delay = 0.0 if math.isnan(delay_ns) else 1.0
    later = max(-50.0, min(50.0, delay_ns)) if has_delay else 0.0
    log_rho = math.log(max(1e-3, min(1e3, rho)))
    unexplained = max(0.0, min(1.0, 1 - quality))
    return [1.0, log_rho, unexplained, has_delay, later, has_delay * log_rho,
            has_delay * unexplained]


def sigmoid(z):
    return 1 / (1 + math.exp(-max(-40.0, min(40.0, z))))


def fit_logistic(X, y, ridge=1e-3, rounds=30):
    n = len(X[0])
    b = [0.0] * n
    for _ in range(rounds):
        g = [0.0] * n
        H = [[ridge if i == j else 0.0 for j in range(n)] for i in range(n)]
        for xi, yi in zip(X, y):
            p = sigmoid(sum(bj * xj for bj, xj in zip(b, xi)))
            w = p * (1 - p)
            for i in range(n):
                g[i] += (yi - p) * xi[i]
                for j in range(n):
                    H[i][j] += w * xi[i] * xi[j]
        for i in range(n):
            g[i] -= ridge * b[i]
        step = solve(H, g)
        b = [bj + sj for bj, sj in zip(b, step)]
        if max(abs(s) for s in step) < 1e-8:
            break
    return b


def solve(A, v):
    n = len(v)
    M = [row[:] + [v[i]] for i, row in enumerate(A)]
    for c in range(n):
        p = max(range(c, n), key=lambda r: abs(M[r][c]))
        M[c], M[p] = M[p], M[c]
        for r in range(n):
            if r != c and M[c][c] != 0:
                f = M[r][c] / M[c][c]
                M[r] = [a - f * b for a, b in zip(M[r], M[c])]
    return [M[i][n] / M[i][i] if M[i][i] else 0.0 for i in range(n)]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("dump")
    ap.add_argument("--threshold-deg", type=float, default=15.0)
    ap.add_argument("--per-room", action="store_true",
                    help="also each room's (seed's) share beyond 30° and beyond the alternatives")
    ap.add_argument("--coefficients", help="comma-separated coefficients to evaluate instead "
                    "of fitting (intercept, ln power, 1 - quality, has delay, delay ns, "
                    "has delay × ln power, has delay × (1 - quality))")
    a = ap.parse_args()
    T = a.threshold_deg
    rows = []
    with open(a.dump) as f:
        for r in csv.DictReader(f):
            cands = []
            for c in filter(None, (r.get("candidates") or "").split(";")):
                e, w, rho, d, kept = c.split(":")
                cands.append((float(e), float(rho), float(d)))
            rows.append((r["algo"], float(r["error_deg"]), float(r["quality"]),
                         r["central"] == "1", cands, int(r["seed"]), float(r["std_deg"]),
                         float(r.get("alt_error_deg") or "nan")))
    print(f"{len(rows)} bearings from {a.dump}")

    # 1. What predicts a wrong chosen direction.
    print("\n## P(chosen > 30°) by the strongest candidate's power over the chosen one's and "
          "quality (count)")
    rho_bins = [0, 0.1, 0.25, 0.5, 0.75, 1.0, 1.5, 1e9]
    q_bins = [0, 0.5, 0.7, 0.85, 1.01]
    print("| ρ \\ quality | " + " | ".join(f"{q_bins[i]}–{q_bins[i+1]}" for i in
                                        range(len(q_bins) - 1)) + " |")
    print("|---" * len(q_bins) + "|")
    for i in range(len(rho_bins) - 1):
        cells = []
        for j in range(len(q_bins) - 1):
            sel = [r for r in rows if q_bins[j] <= r[2] < q_bins[j + 1] and
                   rho_bins[i] <= max([c[1] for c in r[4]] or [0]) < rho_bins[i + 1]]
            bad = sum(r[1] > 30 for r in sel)
            cells.append(f"{100 * bad / len(sel):.1f} % ({len(sel)})" if sel else "–")
        print(f"| {rho_bins[i]}–{rho_bins[i+1] if rho_bins[i+1] < 1e8 else '∞'} | " +
              " | ".join(cells) + " |")

    # 2. The candidate's weight.
    X, y = [], []
    for algo, err, q, central, cands, *_ in rows:
        for e, rho, d in cands:
            X.append(features(rho, d, q))
            y.append(1.0 if err > T and e <= T else 0.0)
    print(f"\n## Candidates: {len(X)}, right ones (chosen > {T}°, candidate ≤ {T}°): "
          f"{int(sum(y))}")
    if a.coefficients:
        b = [float(v) for v in a.coefficients.split(",")]
    else:
        b = fit_logistic(X, y)
    names = ["kAltIntercept", "kAltLogPower", "kAltUnexplained", "kAltHasDelay", "kAltDelay",
             "kAltDelayLogPower", "kAltDelayUnexplained"]
    print("constexpr double " + ", ".join(f"{n} = {v:.4g}" for n, v in zip(names, b)) + ";")
    preds = sorted((sigmoid(sum(bj * xj for bj, xj in zip(b, x))), yy) for x, yy in zip(X, y))
    print("\n| predicted weight (decile of candidates) | mean predicted | observed right |")
    print("|---|---|---|")
    k = len(preds)
    for dec in range(10):
        part = preds[dec * k // 10:(dec + 1) * k // 10]
        if part:
            print(f"| {part[0][0]:.3f}–{part[-1][0]:.3f} | {sum(p for p, _ in part) / len(part):.4f}"
                  f" | {sum(t for _, t in part) / len(part):.4f} ({int(sum(t for _, t in part))}"
                  f" of {len(part)}) |")
    ll = sum(math.log(max(1e-12, p if t else 1 - p)) for p, t in preds)
    base = sum(y) / max(1, len(y))
    ll0 = sum(math.log(max(1e-12, base if t else 1 - base)) for t in y)
    print(f"log-likelihood {ll:.1f} (constant model {ll0:.1f})")

    # 3. Beyond 30° with the alternatives counted.
    print("\n| estimator | central bearings | > 30° | > 30° and beyond its alternatives | "
          "alternatives per bearing | weight on them (mean) | > 30° and beyond every candidate "
          "weighed |")
    print("|---|---|---|---|---|---|---|")
    for algo in sorted({r[0] for r in rows}):
        sel = [r for r in rows if r[0] == algo and r[3]]
        beyond = beyond_alts = beyond_all = n_alts = 0
        wsum = 0.0
        for _, err, q, _, cands, *_ in sel:
            ws = sorted(((sigmoid(sum(bj * xj for bj, xj in zip(b, features(rho, d, q)))), e, rho)
                         for e, rho, d in cands), reverse=True)
            kept = [(w, e) for w, e, rho in ws if w >= MIN_WEIGHT or rho >= 1][:MAX_ALTS]
            n_alts += len(kept)
            wsum += sum(w for w, _ in kept)
            beyond += err > 30
            beyond_alts += err > 30 and all(e > 30 for _, e in kept)
            beyond_all += err > 30 and all(e > 30 for e, _, _ in cands)
        n = max(1, len(sel))
        print(f"| {algo} | {len(sel)} | {100 * beyond / n:.2f} % | {100 * beyond_alts / n:.2f} % "
              f"| {n_alts / n:.2f} | {wsum / n:.3f} | {100 * beyond_all / n:.2f} % |")


    if a.per_room:
        print("\n| estimator | room | central bearings | > 30° | > 30° and beyond its alternatives "
              "(refitted weights) | > 30° and beyond the alternatives it emitted | within 3σ |")
        print("|---|---|---|---|---|---|---|")
        summary = {}
        for algo in sorted({r[0] for r in rows}):
            for seed in sorted({r[5] for r in rows if r[0] == algo}):
                sel = [r for r in rows if r[0] == algo and r[5] == seed and r[3]]
                if not sel:
                    continue
                beyond = beyond_alts = beyond_emitted = within = 0
                for _, err, q, _, cands, _, std, alt_err in sel:
                    ws = sorted(((sigmoid(sum(bj * xj for bj, xj in
                                                 zip(b, features(rho, d, q)))), e, rho)
                                 for e, rho, d in cands), reverse=True)
                    kept = [e for w, e, rho in ws if w >= MIN_WEIGHT or rho >= 1][:MAX_ALTS]
                    beyond += err > 30
                    beyond_alts += err > 30 and all(e > 30 for e in kept)
                    beyond_emitted += err > 30 and not alt_err <= 30
                    within += err <= 3 * std
                n = len(sel)
                summary.setdefault(algo, []).append(
                    (seed, beyond / n, beyond_alts / n, beyond_emitted / n))
                print(f"| {algo} | {seed} | {n} | {100 * beyond / n:.1f} % | "
                      f"{100 * beyond_alts / n:.1f} % | {100 * beyond_emitted / n:.1f} % | "
                      f"{100 * within / n:.1f} % |")
        for algo, v in summary.items():
            ok = sum(x[2] <= 0.02 for x in v)
            ok0 = sum(x[1] <= 0.02 for x in v)
            emitted = sum(x[3] <= 0.02 for x in v)
            worst = sorted(v, key=lambda x: -x[2])[:3]
            print(f"{algo}: rooms ≤ 2 % beyond 30° and beyond the alternatives: {ok} / {len(v)} "
                  f"(emitted: {emitted} / {len(v)}; without the alternatives: {ok0} / {len(v)}); worst: " +
                  ", ".join(f"{s} ({100 * x:.1f} %)" for s, _, x, _ in worst))


if __name__ == "__main__":
    sys.exit(main())
