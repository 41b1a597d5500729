"""The seed paper's figures from gsens in Python: the loop's response, the
hand shaking, the measured phase error against the one predicted from Γ̂,
Γ̂ converging in the streaming calibrator, and the phase error before and
after compensation.

    python python/examples/paper_figures.py --out /tmp/gsens-figures [--seed 1]
"""

from __future__ import annotations

import argparse
import pathlib

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import gsens  # noqa: E402

AXES = "xyz"


def predicted_phase_err_rad(loop: gsens.Loop, accel_mps2, gamma_hz_per_mps2, substeps: int) -> np.ndarray:
    """The model's phase error per log epoch: aᵀΓ held over each epoch's
    loop updates, run through the discrete loop, averaged per epoch (the
    paper's session logs the mean discriminator output)."""
    delta_f_hz = np.repeat(accel_mps2 @ gamma_hz_per_mps2, substeps)
    return loop.filter(delta_f_hz).reshape(-1, substeps).mean(axis=1)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=pathlib.Path, required=True, help="directory for the PNG figures")
    parser.add_argument("--seed", type=int, default=1, help="simulation seed")
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)

    sim = gsens.simulate(seed=args.seed)
    settings = sim.estimate_settings()
    est = gsens.estimate(sim.imu, sim.tracking, **settings)
    print(est)
    doc = est.to_dict()
    loop = gsens.Loop(order=settings["order"], bn_hz=settings["bn_hz"], interval_s=settings["loop_interval_s"])
    f_peak, _ = loop.peak()
    ep = est.epochs()
    t = ep["t_s"]

    # 1. The loop's sensitivity to an oscillator frequency error.
    f_hz = np.geomspace(0.05, 20, 400)
    fig, ax = plt.subplots(figsize=(6, 4))
    ax.loglog(f_hz, np.abs(loop.response(f_hz)))
    lo, hi = loop.half_power_band_hz()
    ax.axvspan(lo, hi, alpha=0.15, label=f"half-power band {lo:.2f}–{hi:.2f} Hz")
    ax.axvline(f_peak, ls="--", lw=0.8, label=f"peak {f_peak:.2f} Hz")
    ax.set(xlabel="frequency [Hz]", ylabel="|φ/Δf| [rad/Hz]", title=f"{loop!r}")
    ax.legend()
    fig.savefig(args.out / "loop_response.png", dpi=120, bbox_inches="tight")

    # 2. The shaking: specific force per axis (gravity removed by its mean).
    fig, axs = plt.subplots(3, 1, sharex=True, figsize=(8, 6))
    for i, a in enumerate(AXES):
        f = sim.imu[f"f{a}_mps2"]
        axs[i].plot(sim.imu["t_s"], f - f.mean(), lw=0.6)
        axs[i].set_ylabel(f"f{a} [m/s²]")
    axs[-1].set_xlabel("t [s]")
    fig.suptitle("hand shaking along x, then y, then z")
    fig.savefig(args.out / "shaking.png", dpi=120, bbox_inches="tight")

    # 3. Measured (channel-averaged) phase error and the prediction from Γ̂.
    gamma = np.nan_to_num(est.gamma_hz_per_mps2)
    substeps = int(round(doc["log_interval_s"] / settings["loop_interval_s"]))
    # The loop rejects a constant Δf (gravity's aᵀΓ) and the oscillator's own
    # drift leaves a slow offset in φ: both are removed, as the estimator's
    # high-pass does, so that the figure shows the g-induced part.
    predicted = predicted_phase_err_rad(loop, ep["accel_mps2"] - ep["accel_mps2"][0], gamma, substeps)
    measured = ep["phase_err_rad"] - np.nanmedian(ep["phase_err_rad"])
    fig, ax = plt.subplots(figsize=(8, 4))
    ax.plot(t, measured, lw=0.5, label="measured (channel mean, median removed)")
    ax.plot(t, predicted, lw=0.8, label="predicted from Γ̂")
    ax.set(xlabel="t [s]", ylabel="phase error [rad]")
    ax.legend()
    fig.savefig(args.out / "phase_error.png", dpi=120, bbox_inches="tight")

    # 4. Γ̂ converging in the streaming calibrator, with ±1σ and the truth.
    cal = gsens.Calibrator(doc["log_interval_s"], **settings)
    history_t, history_g, history_s = [], [], []
    step = 80
    for k in range(0, len(t), step):
        cal.feed_many(ep["accel_mps2"][k : k + step], ep["phase_err_rad"][k : k + step])
        e = cal.estimate()
        history_t.append(t[min(k + step, len(t)) - 1])
        history_g.append(e["gamma_hz_per_mps2"])
        history_s.append(e["sigma_hz_per_mps2"])
    g, s = np.array(history_g), np.array(history_s)
    fig, axs = plt.subplots(3, 1, sharex=True, figsize=(8, 7))
    for i, a in enumerate(AXES):
        axs[i].plot(history_t, g[:, i], label=f"Γ̂{a}")
        axs[i].fill_between(history_t, g[:, i] - s[:, i], g[:, i] + s[:, i], alpha=0.25, label="±1σ (white noise)")
        axs[i].axhline(sim.gamma_hz_per_mps2[i], color="k", ls=":", lw=1, label="truth")
        axs[i].set_ylabel(f"Γ{a} [Hz/(m/s²)]")
    axs[0].legend(loc="lower right")
    axs[-1].set_xlabel("t [s]")
    fig.suptitle("the streaming calibrator converging as each axis is shaken")
    fig.savefig(args.out / "convergence.png", dpi=120, bbox_inches="tight")

    # 5. Compensation: the phase error with the predicted g-induced part removed.
    fig, ax = plt.subplots(figsize=(8, 4))
    ax.plot(t, measured, lw=0.5, label=f"before (RMS {doc['rms_before_rad']:.3f} rad)")
    ax.plot(t, measured - predicted, lw=0.5, label=f"after (RMS {doc['rms_after_rad']:.4f} rad)")
    ax.set(xlabel="t [s]", ylabel="phase error [rad]")
    ax.legend()
    fig.savefig(args.out / "compensation.png", dpi=120, bbox_inches="tight")
    print(f"figures in {args.out}")


if __name__ == "__main__":
    main()
