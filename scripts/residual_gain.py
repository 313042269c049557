#!/usr/bin/env python3
"""The residual monitor's peak factors (params::kResidualPeakFactor, docs/safety.md).

The residual takes its joint velocity from the model-based observer (21)-(23). Along one
operational axis with gains k, k_i and an eigenvalue lambda of Lambda, an unexplained force F
reaches the observer's innovation through G(s) = (k s + b) / (s^2 + k s + b), b = k_i / lambda, and
then the residual's own filter K / (s + K). A bound B on |F| bounds the residual by ||h||_1 B, the
L1 norm of the impulse response of the two in series (for a first-order filter alone it is 1).
This prints ||h||_1 over the range of b the arm meets, for each axis group and filter bandwidth:
the translational rows (k = 108, k_i = 2000, Lambda's translational eigenvalues 0.2-40 kg) set the
factor of J1-J3, whose velocities come from those rows alone (J is block lower-triangular); the
rotational rows (k = 32, k_i = 3000, 0.03-10 kg m^2) set the wrist's.

    python3 scripts/residual_gain.py
"""
import sys

ROOT = __file__.rsplit("/scripts/", 1)[0]


def params(name, n):
    """The first n numbers of a params:: array (osc/control/params.hpp)."""
    text = open(ROOT + "/firmware/control/include/osc/control/params.hpp").read()
    body = text.split("constexpr double " + name + "[")[1].split("{", 1)[1].split("}", 1)[0]
    return [float(v) for v in body.split(",")[:n]]


def l1_norm(K, k, b, T=1.5, dt=1e-5):
    """||h||_1 of K / (s + K) * (k s + b) / (s^2 + k s + b), by exact-enough integration."""
    x1, x2, r, total = 0.0, 1.0, 0.0, 0.0  # an impulse into G's controllable form
    for _ in range(int(T / dt)):
        y = b * x1 + k * x2
        r += dt * K * (y - r)
        total += abs(r) * dt
        x1, x2 = x1 + dt * x2, x2 + dt * (-b * x1 - k * x2)
    return total


def main():
    k, ki, K = params("kK", 6), params("kKi", 6), params("kResidualGain", 6)
    factor = params("kResidualPeakFactor", 6)
    groups = [("J1-J3 (translational rows)", k[0], ki[0], K[0], factor[0], (0.2, 40)),
              ("J4-J6 (rotational rows)", k[3], ki[3], K[3], factor[3], (0.03, 10))]
    ok = True
    print("| joints | k | k_i | K | Lambda eigenvalues | largest L1 norm | kResidualPeakFactor |")
    print("|---|---:|---:|---:|---|---:|---:|")
    for name, kk, kki, KK, f, (lo, hi) in groups:
        worst, lam = 0.0, lo
        while lam <= hi * 1.0001:
            worst = max(worst, l1_norm(KK, kk, kki / lam))
            lam *= 1.5
        print(f"| {name} | {kk:g} | {kki:g} | {KK:g} | {lo:g} - {hi:g} | {worst:.3f} | {f:g} |")
        ok = ok and worst <= f
    if not ok:
        print("a peak factor is below its L1 norm", file=sys.stderr)
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
