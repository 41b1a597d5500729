#!/usr/bin/env python3
"""An independent simulator of a g-sensitivity calibration session (numpy only).

Written from the physics, not from gsens's own simulator, so that gsens's
checks can be tested on data made another way. It writes gsens's CSV formats
(docs/conventions.md, "IMU log" and "Tracking log") and the truth:

    imu.csv        t_s,fx_mps2,fy_mps2,fz_mps2
    tracking.csv   t_s,channel,prn,cn0_dbhz,elev_deg,phase_err_rad
    truth.json     {"gamma_hz_per_mps2": [..], "generator": ..., the settings, per-channel facts}

Model (all deterministic from --seed):

* Specific force, board level, z up: f(t) = (0, 0, g0) + shaking, g0 = 9.80665 m/s².
  Shaking is a list of segments, one after the other with rests of --rest-s
  between them (and before the first and after the last): a sinusoid
  A·sin(2π(t − t0)/P) on one axis for D seconds, its amplitude raised and
  lowered over one period by a half-cosine ramp (a hand does not start at
  full amplitude). Several segments per axis are allowed (two rates per axis).
  The IMU log samples f at i/rate (no time offset) plus white noise of σ
  --imu-noise-mps2 per axis.
* Oscillator: Δf(t) = f(t)ᵀΓ + w(t) [Hz], w a random walk of
  --osc-rw-hz-per-sqrt-s (increment σ = q·√T per loop update), added to every
  channel's replica frequency (the same Δf for all channels).
* Satellites, static antenna: Doppler d(t) = A·sin(Ω·(t_c − t)) with
  Ω = 2π/(11 h 58 min) (the orbit seen from the rotating Earth, roughly),
  A ∈ [2.5, 4.5] kHz and t_c ∈ [−1.5, 1.5] h per satellite, so the Doppler
  rate −A·Ω·cos(…) lies in about [−0.65, −0.2] Hz/s (≤ 0, as for every pass:
  the range rate only grows) and a 2nd-order loop keeps its steady-state
  error −2π·ḋ/ωn² [rad].
* Carrier loop per channel, updated once per T (--loop-interval-s).
  Integration k spans [(k − ½)T, (k + ½)T], centred on t = kT. During it the
  replica runs at the loop's command c_k plus Δf_k; the signal at d_k (both
  taken at the centre). With e_k the true phase error θ_signal − θ_replica at
  the start of the interval and ν = d_k − c_k − Δf_k:

      φ_k     = e_k + π·T·ν                        (phase error at the centre)
      e_{k+1} = e_k + 2π·T·ν
      I + jQ  = √(2·C·T)·sinc(ν·T)·exp(jφ_k) + n_I + j·n_Q,   n ~ N(0, 1)

  so the coherent SNR |signal|²/E|n|² is C·T with C = 10^(C/N0 / 10) Hz.
  Discriminator: atan(Q/I) (two-quadrant Costas, --discriminator atan) or
  atan2(Q, I) (four-quadrant, --discriminator atan2), in rad.
  Loop filter F(s) = c0 + c1/s + c2/s² [rad/s per rad]:
  2nd order c0 = 2ζωn, c1 = ωn², c2 = 0 with ζ = 1/√2 and ωn = 2·Bn/(ζ + 1/(4ζ));
  3rd order (Kaplan & Hegarty) c0 = b3·ωn, c1 = a3·ωn², c2 = ωn³, a3 = 1.1,
  b3 = 2.4, ωn = Bn·4(a3b3 − 1)/(a3b3² + a3² − b3). Discretised here with
  trapezoidal integrators of the discriminator output u_k:
      v1_k = v1_{k−1} + T(u_k + u_{k−1})/2,   v2_k = v2_{k−1} + T(v1_k + v1_{k−1})/2
      c_{k+1} = (c0·u_k + c1·v1_k + c2·v2_k)/2π        (one update of latency)
  Each loop starts locked (command on the Doppler, integrators holding the
  Doppler and its rate) --preroll-s before t = 0 with the board at rest, so
  its start-up is over when the logs begin.
* Logs: every T_log (--log-interval-s, a multiple of T) the tracking log has
  one row per channel, stamped with the centre of the latest integration,
  holding that integration's discriminator output ("last"). cn0_dbhz is the
  true C/N0, elev_deg a fixed elevation per satellite (informational).
* Truth extras: per channel the largest |true phase error| at the interval
  centres and the number of times the true error left the discriminator's
  unambiguous range (±π/2 atan, ±π atan2; 0 means no slip was possible), and
  the peak |g-induced phase error| of the same loop fed Δf = fᵀΓ alone
  (no noise, no Doppler): what a calibrator's φ_aᵀΓ should peak at.

Examples:
    scripts/indep_sim.py --out /tmp/s --seed 1 --shake x:1.1:6:20 --shake y:0.9:6:20
    scripts/indep_sim.py --out /tmp/s --config shake.json
        shake.json: {"rest_s": 4, "segments": [{"axis": "x", "period_s": 1.1,
                     "amplitude_mps2": 6, "duration_s": 20}, ...]}
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys

import numpy as np

G0_MPS2 = 9.80665
ORBIT_RATE_RAD_PER_S = 2.0 * math.pi / (11 * 3600 + 58 * 60)
AXES = {"x": 0, "y": 1, "z": 2}


def loop_coefficients(order: int, bn_hz: float) -> tuple[float, float, float, float]:
    """(c0 [1/s], c1 [1/s²], c2 [1/s³], ωn [rad/s]) of the continuous loop filter."""
    if order == 2:
        zeta = 1.0 / math.sqrt(2.0)
        wn = 2.0 * bn_hz / (zeta + 1.0 / (4.0 * zeta))
        return 2.0 * zeta * wn, wn * wn, 0.0, wn
    if order == 3:
        a3, b3 = 1.1, 2.4
        wn = bn_hz * 4.0 * (a3 * b3 - 1.0) / (a3 * b3 * b3 + a3 * a3 - b3)
        return b3 * wn, a3 * wn * wn, wn**3, wn
    raise ValueError(f"--order must be 2 or 3, not {order}")


def parse_shake(text: str) -> dict:
    """'axis:period_s:amplitude_mps2:duration_s' → a segment."""
    parts = text.split(":")
    if len(parts) != 4 or parts[0] not in AXES:
        raise ValueError(f"--shake {text!r}: expected axis:period_s:amplitude_mps2:duration_s, axis x, y or z")
    return {
        "axis": parts[0],
        "period_s": float(parts[1]),
        "amplitude_mps2": float(parts[2]),
        "duration_s": float(parts[3]),
    }


def schedule(segments: list[dict], rest_s: float) -> tuple[list[dict], float]:
    """Start times of the segments, rests between; returns (segments, duration)."""
    t = rest_s
    out = []
    for s in segments:
        if s["axis"] not in AXES or s["period_s"] <= 0 or s["duration_s"] <= 0:
            raise ValueError(f"bad shaking segment {s}")
        out.append(dict(s, start_s=t))
        t += s["duration_s"] + rest_s
    return out, t


def shaking_mps2(t_s: np.ndarray, segments: list[dict]) -> np.ndarray:
    """Specific force of the board (gravity plus shaking), shape (len(t), 3)."""
    f = np.zeros((t_s.size, 3))
    f[:, 2] = G0_MPS2
    for s in segments:
        tau = t_s - s["start_s"]
        inside = (tau >= 0) & (tau <= s["duration_s"])
        p, d = s["period_s"], s["duration_s"]
        ramp_s = min(p, d / 2)
        # Half-cosine ramps up and down over one period.
        env = np.clip(np.minimum(tau, d - tau) / ramp_s, 0.0, 1.0)
        env = 0.5 - 0.5 * np.cos(math.pi * env)
        f[:, AXES[s["axis"]]] += np.where(inside, s["amplitude_mps2"] * env * np.sin(2 * math.pi * tau / p), 0.0)
    return f


def simulate(cfg: dict) -> dict:
    """Run the session; returns the arrays and the truth."""
    rng = np.random.default_rng(cfg["seed"])
    t_loop = cfg["loop_interval_s"]
    n_sub = int(round(cfg["log_interval_s"] / t_loop))
    if n_sub < 1 or abs(n_sub * t_loop - cfg["log_interval_s"]) > 1e-9 * cfg["log_interval_s"]:
        raise ValueError("--log-interval-s must be a whole multiple of --loop-interval-s")
    segments, duration_s = schedule(cfg["segments"], cfg["rest_s"])
    if cfg.get("duration_s"):
        duration_s = max(duration_s, cfg["duration_s"])
    gamma = np.asarray(cfg["gamma_hz_per_mps2"], dtype=float)
    c0, c1, c2, wn = loop_coefficients(cfg["order"], cfg["bn_hz"])
    n_ch = cfg["channels"]
    cn0 = np.asarray(cfg["cn0_dbhz"], dtype=float)
    if cn0.size == 1:
        cn0 = np.full(n_ch, cn0.item())
    if cn0.size != n_ch:
        raise ValueError(f"--cn0-dbhz gives {cn0.size} values for {n_ch} channels")
    amp = np.sqrt(2.0 * 10.0 ** (cn0 / 10.0) * t_loop)

    # Satellites: PRNs, Doppler amplitude and closest-approach time, elevation.
    prns = np.sort(rng.choice(np.arange(1, 33), size=n_ch, replace=False))
    dop_amp_hz = rng.uniform(2500.0, 4500.0, n_ch)
    t_c_s = rng.uniform(-5400.0, 5400.0, n_ch)
    elev_deg = np.round(rng.uniform(15.0, 85.0, n_ch), 1)

    def doppler_hz(t):
        return dop_amp_hz * np.sin(ORBIT_RATE_RAD_PER_S * (t_c_s - t))

    def doppler_rate_hz_per_s(t):
        return -dop_amp_hz * ORBIT_RATE_RAD_PER_S * np.cos(ORBIT_RATE_RAD_PER_S * (t_c_s - t))

    # Loop states for n_ch channels plus one noise-free, Doppler-free loop fed
    # the g-induced Δf alone (the last column).
    k0 = -int(round(cfg["preroll_s"] / t_loop))
    k_end = int(round(duration_s / cfg["log_interval_s"])) * n_sub
    t_start = k0 * t_loop
    d0 = np.append(doppler_hz(t_start), 0.0)
    r0 = np.append(doppler_rate_hz_per_s(t_start), 0.0)
    f_rest = np.array([0.0, 0.0, G0_MPS2])
    df0 = float(f_rest @ gamma)
    cmd = d0 - df0  # command that cancels the Doppler and the oscillator's bias
    if c2 > 0:
        v1 = 2 * math.pi * r0 / c2
        v2 = (2 * math.pi * cmd - c1 * v1) / c2
    else:
        v2 = np.zeros(n_ch + 1)
        v1 = 2 * math.pi * cmd / c1
    u_prev = np.zeros(n_ch + 1)
    e = np.zeros(n_ch + 1)
    osc_rw_hz = 0.0
    half = math.pi / 2 if cfg["discriminator"] == "atan" else math.pi
    max_abs = np.zeros(n_ch + 1)
    wraps = np.zeros(n_ch, dtype=int)
    outside = np.zeros(n_ch, dtype=bool)

    n_steps = k_end - k0 + 1
    t_all = (k0 + np.arange(n_steps)) * t_loop
    force = shaking_mps2(t_all, segments)
    df_g = force @ gamma
    osc_steps = rng.standard_normal(n_steps) * cfg["osc_rw_hz_per_sqrt_s"] * math.sqrt(t_loop)
    noise = rng.standard_normal((n_steps, n_ch, 2))
    n_rows = k_end // n_sub
    log = np.zeros((n_rows, n_ch))
    row = 0
    for i in range(n_steps):
        k = k0 + i
        t = t_all[i]
        osc_rw_hz += osc_steps[i]
        dop = np.append(doppler_hz(t), 0.0)
        df = np.full(n_ch + 1, df_g[i])
        df[:n_ch] += osc_rw_hz
        nu = dop - cmd - df
        phi = e + math.pi * t_loop * nu
        e = e + 2 * math.pi * t_loop * nu
        # Correlators of the noisy channels; the reference loop sees φ itself.
        gain = amp * np.sinc(nu[:n_ch] * t_loop)
        i_corr = gain * np.cos(phi[:n_ch]) + noise[i, :, 0]
        q_corr = gain * np.sin(phi[:n_ch]) + noise[i, :, 1]
        u = np.empty(n_ch + 1)
        if cfg["discriminator"] == "atan":
            u[:n_ch] = np.arctan(q_corr / i_corr)
        else:
            u[:n_ch] = np.arctan2(q_corr, i_corr)
        u[n_ch] = phi[n_ch]
        if k >= 0:
            max_abs = np.maximum(max_abs, np.abs(phi))
            now = np.abs(phi[:n_ch]) > half
            wraps += now & ~outside
            outside = now
            if k > 0 and k % n_sub == 0:
                log[row] = u[:n_ch]
                row += 1
        v1_new = v1 + t_loop * (u + u_prev) / 2
        v2 = v2 + t_loop * (v1_new + v1) / 2
        v1 = v1_new
        u_prev = u
        cmd = (c0 * u + c1 * v1 + c2 * v2) / (2 * math.pi)

    t_log = (np.arange(1, n_rows + 1) * n_sub) * t_loop
    n_imu = int(math.floor(duration_s * cfg["imu_rate_hz"])) + 1
    t_imu = np.arange(n_imu) / cfg["imu_rate_hz"]
    imu = shaking_mps2(t_imu, segments) + rng.standard_normal((n_imu, 3)) * cfg["imu_noise_mps2"]

    truth = {
        "gamma_hz_per_mps2": gamma.tolist(),
        "generator": "scripts/indep_sim.py",
        "seed": cfg["seed"],
        "duration_s": t_log[-1] if n_rows else 0.0,
        "order": cfg["order"],
        "bn_hz": cfg["bn_hz"],
        "natural_frequency_hz": wn / (2 * math.pi),
        "loop_coeffs": {"c0_per_s": c0, "c1_per_s2": c1, "c2_per_s3": c2},
        "loop_interval_s": t_loop,
        "log_interval_s": cfg["log_interval_s"],
        "logged_phase": "last",
        "discriminator": cfg["discriminator"],
        "imu_rate_hz": cfg["imu_rate_hz"],
        "imu_noise_mps2": cfg["imu_noise_mps2"],
        "imu_time_offset_s": 0.0,
        "osc_rw_hz_per_sqrt_s": cfg["osc_rw_hz_per_sqrt_s"],
        "preroll_s": cfg["preroll_s"],
        "rest_s": cfg["rest_s"],
        "segments": segments,
        "peak_g_induced_phase_err_rad": float(max_abs[n_ch]),
        "channels": [
            {
                "channel": c,
                "prn": int(prns[c]),
                "cn0_dbhz": float(cn0[c]),
                "elev_deg": float(elev_deg[c]),
                "doppler_amplitude_hz": float(dop_amp_hz[c]),
                "closest_approach_s": float(t_c_s[c]),
                "doppler_rate_at_start_hz_per_s": float(doppler_rate_hz_per_s(0.0)[c]),
                "max_abs_true_phase_err_rad": float(max_abs[c]),
                "discriminator_range_exits": int(wraps[c]),
            }
            for c in range(n_ch)
        ],
    }
    return {
        "t_imu": t_imu,
        "imu": imu,
        "t_log": t_log,
        "log": log,
        "prns": prns,
        "cn0": cn0,
        "elev_deg": elev_deg,
        "truth": truth,
    }


def write_session(out_dir: str, s: dict, decimals: int | None = None) -> None:
    """imu.csv, tracking.csv and truth.json in gsens's formats; the specific
    force and the phase error rounded to `decimals` places if given (small
    files: 6 places are 1e-6 rad and m/s², far below the noise)."""
    os.makedirs(out_dir, exist_ok=True)
    imu, log = s["imu"], s["log"]
    if decimals is not None:
        imu, log = np.round(imu, decimals), np.round(log, decimals)
    # Python floats print the shortest decimal that reads back to the same bits.
    with open(os.path.join(out_dir, "imu.csv"), "w") as f:
        f.write("t_s,fx_mps2,fy_mps2,fz_mps2\n")
        for t, (x, y, z) in zip(s["t_imu"].tolist(), imu.tolist()):
            f.write(f"{t!r},{x!r},{y!r},{z!r}\n")
    prns, cn0, elev = s["prns"].tolist(), s["cn0"].tolist(), s["elev_deg"].tolist()
    with open(os.path.join(out_dir, "tracking.csv"), "w") as f:
        f.write("t_s,channel,prn,cn0_dbhz,elev_deg,phase_err_rad\n")
        for t, phis in zip(s["t_log"].tolist(), log.tolist()):
            for c, p in enumerate(phis):
                f.write(f"{t!r},{c},{prns[c]},{cn0[c]!r},{elev[c]!r},{p!r}\n")
    with open(os.path.join(out_dir, "truth.json"), "w") as f:
        json.dump(s["truth"], f, indent=2)
        f.write("\n")


def parse_args(argv: list[str]) -> dict:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--out", required=True, help="output directory")
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--config", help="JSON with 'segments' (and optionally 'rest_s' and any other option)")
    p.add_argument("--shake", action="append", default=[], help="axis:period_s:amplitude_mps2:duration_s (repeat)")
    p.add_argument("--rest-s", type=float, default=4.0, help="rest before, between and after segments")
    p.add_argument("--duration-s", type=float, default=0.0, help="at least this long (rest at the end)")
    p.add_argument("--gamma", default="0.09,-0.06,0.05", help="Γ [Hz/(m/s²)], x,y,z")
    p.add_argument("--order", type=int, default=2, choices=[2, 3])
    p.add_argument("--bn-hz", type=float, default=3.0)
    p.add_argument("--loop-interval-s", type=float, default=0.001)
    p.add_argument("--log-interval-s", type=float, default=0.025)
    p.add_argument("--discriminator", default="atan", choices=["atan", "atan2"])
    p.add_argument("--channels", type=int, default=6)
    p.add_argument("--cn0-dbhz", default="45", help="one value for all channels or one per channel, comma-separated")
    p.add_argument("--imu-rate-hz", type=float, default=200.0)
    p.add_argument("--imu-noise-mps2", type=float, default=0.02)
    p.add_argument("--osc-rw-hz-per-sqrt-s", type=float, default=0.005)
    p.add_argument("--preroll-s", type=float, default=15.0)
    p.add_argument("--decimals", type=int, help="round the specific force and phase error to this many places")
    a = p.parse_args(argv)
    cfg = {
        "seed": a.seed,
        "rest_s": a.rest_s,
        "duration_s": a.duration_s,
        "gamma_hz_per_mps2": [float(v) for v in a.gamma.split(",")],
        "order": a.order,
        "bn_hz": a.bn_hz,
        "loop_interval_s": a.loop_interval_s,
        "log_interval_s": a.log_interval_s,
        "discriminator": a.discriminator,
        "channels": a.channels,
        "cn0_dbhz": [float(v) for v in a.cn0_dbhz.split(",")],
        "imu_rate_hz": a.imu_rate_hz,
        "imu_noise_mps2": a.imu_noise_mps2,
        "osc_rw_hz_per_sqrt_s": a.osc_rw_hz_per_sqrt_s,
        "preroll_s": a.preroll_s,
        "segments": [parse_shake(s) for s in a.shake],
    }
    if a.config:
        with open(a.config) as f:
            cfg.update(json.load(f))
    if len(cfg["gamma_hz_per_mps2"]) != 3:
        p.error("--gamma needs three values")
    return {"out": a.out, "decimals": a.decimals, **cfg}


def main(argv: list[str]) -> int:
    cfg = parse_args(argv)
    try:
        s = simulate(cfg)
    except ValueError as err:
        print(f"indep_sim: {err}", file=sys.stderr)
        return 2
    write_session(cfg["out"], s, cfg["decimals"])
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
