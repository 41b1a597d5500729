//! The pieces the joint fit ([`crate::joint_fit`]) is built of: the batch
//! pass that feeds every epoch through the loop models, the global search of
//! the IMU time offset that starts it, and the stated loop scaled.
//!
//! The time offset τ (IMU stamp minus true time): the loop model and the
//! high-pass are time-invariant, so φ_a for an offset τ is the φ_a series at
//! τ = 0 shifted by τ. The shift is evaluated by cubic (Catmull–Rom)
//! interpolation of that series (φ_a is band-limited by the loop to a few Hz,
//! far below the log rate), so the search costs one loop-model pass: the
//! residual sum of squares min_Γ Σ (φ_k − φ_a,k(τ)ᵀΓ)² over a grid of τ, refined
//! by golden section (a variable-projection estimate: Γ is eliminated in
//! closed form for each τ).
//!
//! The interpolated series is linear in φ_a: with the shift τ/T = i + u (i
//! whole, 0 ≤ u < 1) and Catmull–Rom's weights w_j(u) on the samples k+i−1+j
//! (j = 0…3), the normal equations at τ are
//! AᵀA(τ) = Σ_j Σ_l w_j w_l C(i−1+j, l−j) and Aᵀφ(τ) = Σ_j w_j b(i−1+j), from the
//! lagged sums C(m, d) = Σ_k φ_a[k+m] φ_a[k+m+d]ᵀ and b(m) = Σ_k φ_k φ_a[k+m]
//! over the used epochs k. They are summed once for every whole shift m the
//! search can reach; a candidate τ then costs a few 3×3 products, not a pass
//! over the log.

use crate::estimate::build_model;
use crate::{CalibError, EpochSeries, EstimateSettings};
use gsens_core::FedEpoch;
use gsens_core::LoopModel;
use gsens_core::LoopSpec;
use gsens_core::{AxisStage, Calibrator};
use gsens_core::{BatchLeastSquares, NormalEquations};
use rayon::prelude::*;

/// Runs the batch estimator over the series; returns every epoch as fed
/// (high-passed φ and φ_a, used or not) and the normal equations.
///
/// The calibrator's work, [`Calibrator::feed`] epoch by epoch, in two kinds
/// of task: each axis's prefilter ([`gsens_core::compensate_interpolation`]'s
/// a_k + c·(2a_k − a_{k−1} − a_{k+1})), loop model and φ_a high-pass
/// ([`Calibrator::axis_stages`]) is a recursion of its own, and the phase's
/// high-pass, the gap filling and the normal equations
/// ([`Calibrator::feed_regressed`]) follow in epoch order. The epochs go in
/// blocks of [`BATCH_BLOCK_EPOCHS`]: while one block's epochs are fed, the
/// next block's three axes are computed, all four as rayon tasks. Every
/// recursion sees its inputs in epoch order with the operations of `feed`,
/// so the result is `feed`'s, bit for bit, on any pool.
pub(crate) fn batch_pass(
    series: &EpochSeries,
    settings: &EstimateSettings,
) -> Result<(Vec<FedEpoch>, NormalEquations), CalibError> {
    let model = build_model(series.log_interval_s, settings)?;
    let c = model.interpolation_compensation();
    let skip = crate::estimate::warmup_epochs(settings, series.log_interval_s);
    let mut cal = Calibrator::new(model, BatchLeastSquares::new(), skip, settings.highpass_hz, series.log_interval_s);
    let mut axes = cal.axis_stages();
    let accel = series.accel_mps2;
    let n = accel.len().min(series.phase_err_rad.len());
    let block_of = |b: usize| b * BATCH_BLOCK_EPOCHS..((b + 1) * BATCH_BLOCK_EPOCHS).min(n);
    let blocks = n.div_ceil(BATCH_BLOCK_EPOCHS);
    let mut fed: Vec<FedEpoch> = Vec::with_capacity(n);
    let (mut cur, mut next) = (AxisBlock::default(), AxisBlock::default());
    if blocks > 0 {
        cur.regress(&mut axes, accel, c, block_of(0));
    }
    for b in 0..blocks {
        let range = block_of(b);
        rayon::join(
            || {
                let phases = &series.phase_err_rad[range];
                let len = phases.len();
                let [(rx, hx), (ry, hy), (rz, hz)] = &cur.columns;
                let (rx, ry, rz, hx, hy, hz) = (&rx[..len], &ry[..len], &rz[..len], &hx[..len], &hy[..len], &hz[..len]);
                for (j, p) in phases.iter().enumerate() {
                    fed.push(cal.feed_regressed(&[rx[j], ry[j], rz[j]], &[hx[j], hy[j], hz[j]], *p));
                }
            },
            || {
                if b + 1 < blocks {
                    next.regress(&mut axes, accel, c, block_of(b + 1));
                }
            },
        );
        std::mem::swap(&mut cur, &mut next);
    }
    Ok((fed, *cal.estimator().normal_equations()))
}

/// The epochs of one block of [`batch_pass`].
pub(crate) const BATCH_BLOCK_EPOCHS: usize = 4096;

/// One block of epochs' regressors, axis by axis: the raw φ_a,i and the
/// high-passed one.
#[derive(Default)]
struct AxisBlock {
    columns: [(Vec<f64>, Vec<f64>); 3],
}

impl AxisBlock {
    /// Runs each axis's stage over the epochs `range` of `accel`, prefiltered
    /// with coefficient `c` (0: not at all) as [`model_input`] prefilters the
    /// whole of `accel`, the three axes as rayon tasks.
    ///
    /// [`model_input`]: crate::estimate::model_input
    fn regress(&mut self, axes: &mut [AxisStage; 3], accel: &[[f64; 3]], c: f64, range: std::ops::Range<usize>) {
        let n = accel.len();
        let filtered = c != 0.0 && n >= 2;
        axes.par_iter_mut().zip(self.columns.par_iter_mut()).enumerate().for_each(|(i, (stage, (raw, hp)))| {
            raw.resize(range.len(), 0.0);
            hp.resize(range.len(), 0.0);
            // The samples before, at and after epoch k (a missing neighbour
            // at the ends is the sample itself).
            let Some(first) = accel.get(range.start) else { return };
            let mut cur = first[i];
            let mut prev = if range.start > 0 { accel[range.start - 1][i] } else { cur };
            for ((k, r), h) in range.clone().zip(raw.iter_mut()).zip(hp.iter_mut()) {
                let next = if k + 1 < n { accel[k + 1][i] } else { cur };
                let a = if filtered { gsens_core::interpolation_compensated(prev, cur, next, c) } else { cur };
                (*r, *h) = stage.step(a);
                (prev, cur) = (cur, next);
            }
        });
    }
}

/// RSS of the least-squares fit from normal equations: φᵀφ − bᵀ(AᵀA)⁺b.
fn rss(normal: &NormalEquations) -> f64 {
    normal.rss(&{
        let (pinv, _) = normal.pseudo_inverse(gsens_core::RANK_TOL);
        pinv * normal.atb
    })
}

/// Catmull–Rom interpolation of a uniformly sampled series at fractional
/// index `x`, point by point: the reference [`Shift`] and the lagged sums are
/// tested against.
#[cfg(test)]
fn catmull_rom(y: &[[f64; 3]], x: f64) -> [f64; 3] {
    let n = y.len() as isize;
    let i = x.floor() as isize;
    let u = x - i as f64;
    let at = |k: isize| y[k.clamp(0, n - 1) as usize];
    let (p0, p1, p2, p3) = (at(i - 1), at(i), at(i + 1), at(i + 2));
    let w = catmull_rom_weights(u);
    [0, 1, 2].map(|c| w[0] * p0[c] + w[1] * p1[c] + w[2] * p2[c] + w[3] * p3[c])
}

/// A uniformly sampled series shifted by a fixed number of samples s = i + u
/// (i whole, 0 ≤ u < 1), by Catmull–Rom interpolation: the value at k + s is
/// Σ_j w_j(u)·y[k+i−1+j] ([`catmull_rom_weights`]), the same four weights at
/// every k (indices clamped to the series).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Shift {
    whole: isize,
    weights: [f64; 4],
}

impl Shift {
    /// The shift by `samples` (any sign).
    pub(crate) fn samples(samples: f64) -> Self {
        let i = samples.floor();
        Shift { whole: i as isize, weights: catmull_rom_weights(samples - i) }
    }

    /// The shifted series at `k`, of a series of `n` samples read by `y`.
    #[inline]
    pub(crate) fn at(&self, n: usize, k: usize, y: impl Fn(usize) -> [f64; 3]) -> [f64; 3] {
        let last = n as isize - 1;
        let base = k as isize + self.whole - 1;
        let mut v = [0.0; 3];
        for (j, w) in self.weights.iter().enumerate() {
            let p = y((base + j as isize).clamp(0, last) as usize);
            for c in 0..3 {
                v[c] += w * p[c];
            }
        }
        v
    }
}

/// Catmull–Rom's weights on the samples i−1, i, i+1, i+2 for the point
/// i + u (0 ≤ u < 1): the cubic ½·(2p₁ + (p₂ − p₀)u + (2p₀ − 5p₁ + 4p₂ − p₃)u² +
/// (−p₀ + 3p₁ − 3p₂ + p₃)u³) collected by sample.
pub(crate) fn catmull_rom_weights(u: f64) -> [f64; 4] {
    let (u2, u3) = (u * u, u * u * u);
    [0.5 * (-u + 2.0 * u2 - u3), 0.5 * (2.0 - 5.0 * u2 + 3.0 * u3), 0.5 * (u + 4.0 * u2 - 3.0 * u3), 0.5 * (-u2 + u3)]
}

/// Golden-section minimization of `f` on \[a, b\].
fn golden(mut a: f64, mut b: f64, tol: f64, mut f: impl FnMut(f64) -> f64) -> f64 {
    let r = (5f64.sqrt() - 1.0) / 2.0;
    let mut x1 = b - r * (b - a);
    let mut x2 = a + r * (b - a);
    let (mut f1, mut f2) = (f(x1), f(x2));
    while b - a > tol {
        if f1 < f2 {
            b = x2;
            x2 = x1;
            f2 = f1;
            x1 = b - r * (b - a);
            f1 = f(x1);
        } else {
            a = x1;
            x1 = x2;
            f1 = f2;
            x2 = a + r * (b - a);
            f2 = f(x2);
        }
    }
    0.5 * (a + b)
}

/// Grid search then golden-section refinement of `f` on \[lo, hi\]; returns the
/// minimizer (the first smallest grid point starts the refinement).
fn minimize_1d(lo: f64, hi: f64, grid: usize, tol: f64, f: impl Fn(f64) -> f64) -> f64 {
    let step = (hi - lo) / grid as f64;
    let (mut best_x, mut best_f) = (lo, f64::INFINITY);
    for i in 0..=grid {
        let x = lo + i as f64 * step;
        let v = f(x);
        if v < best_f {
            best_f = v;
            best_x = x;
        }
    }
    golden((best_x - step).max(lo), (best_x + step).min(hi), tol, &f)
}

/// The profile of the RSS over the time-offset correction δτ for one batch pass.
pub(crate) struct OffsetProfile {
    pub(crate) dtau_s: f64,
}

/// C(m, d) for d = 0…3 (3×3 each).
type Lags = [[[f64; 3]; 3]; 4];

/// The lagged sums of the used epochs for every whole shift `m` in
/// `m_lo..=m_hi` (module documentation): `c[m − m_lo][d]` = C(m, d) for
/// d = 0…3 with m + d ≤ m_hi (the others are never needed; zero), `b[m − m_lo]` = b(m).
struct LaggedSums {
    m_lo: isize,
    c: Vec<Lags>,
    b: Vec<[f64; 3]>,
    btb: f64,
    n: u64,
}

impl LaggedSums {
    /// Every k + m for m in `m_lo..=m_hi` must lie in `phi_a` (the caller's margin).
    fn new(phi_a: &[[f64; 3]], phi: &[f64], used: &[usize], m_lo: isize, m_hi: isize) -> Self {
        use rayon::prelude::*;
        let sums: Vec<(Lags, [f64; 3])> = (m_lo..=m_hi)
            .into_par_iter()
            .map(|m| {
                let mut c: Lags = [[[0.0; 3]; 3]; 4];
                let mut b = [0.0; 3];
                let lags = ((m_hi - m) as usize).min(3);
                for (&k, &p) in used.iter().zip(phi) {
                    let at = (k as isize + m) as usize;
                    let x = phi_a[at];
                    for (d, cd) in c.iter_mut().enumerate().take(lags + 1) {
                        let y = phi_a[at + d];
                        for (r, row) in cd.iter_mut().enumerate() {
                            for (q, v) in row.iter_mut().enumerate() {
                                *v += x[r] * y[q];
                            }
                        }
                    }
                    for r in 0..3 {
                        b[r] += p * x[r];
                    }
                }
                (c, b)
            })
            .collect();
        let (c, b) = sums.into_iter().unzip();
        LaggedSums { m_lo, c, b, btb: phi.iter().map(|p| p * p).sum(), n: used.len() as u64 }
    }

    /// The normal equations of the series shifted by `shift` samples.
    fn normal_at(&self, shift: f64) -> NormalEquations {
        let Shift { whole, weights: w } = Shift::samples(shift);
        let base = (whole - 1 - self.m_lo) as usize;
        let mut ne = NormalEquations { btb: self.btb, n: self.n, ..NormalEquations::default() };
        for j in 0..4 {
            for r in 0..3 {
                ne.atb[r] += w[j] * self.b[base + j][r];
            }
            for l in j..4 {
                let c = &self.c[base + j][l - j];
                let wjl = w[j] * w[l];
                for r in 0..3 {
                    for q in 0..3 {
                        // C(j, l) and, for l ≠ j, its transpose C(l, j).
                        ne.ata[(r, q)] += wjl * c[r][q];
                        if l != j {
                            ne.ata[(q, r)] += wjl * c[r][q];
                        }
                    }
                }
            }
        }
        ne
    }
}

pub(crate) fn offset_profile(fed: &[FedEpoch], t: f64, max_abs_s: f64) -> Result<OffsetProfile, CalibError> {
    let reach = (max_abs_s / t).ceil() as usize;
    let margin = reach + 2;
    // φ_a and the used epochs in epoch order (rayon's collect keeps it).
    let phi_a: Vec<[f64; 3]> = fed.par_iter().map(|e| e.phi_a).collect();
    let mut used: Vec<usize> = (margin..fed.len().saturating_sub(margin))
        .into_par_iter()
        .filter(|&k| fed[k].used && fed[k].phase_err_rad.is_some())
        .collect();
    if used.len() < 10 {
        return Err(CalibError::TooShortForOffsetSearch { max_abs_s, epochs: used.len() });
    }
    // Long logs: a regular subset of at most 40 000 epochs pins τ as well.
    let stride = used.len().div_ceil(40_000).max(1);
    if stride > 1 {
        used = used.into_iter().step_by(stride).collect();
    }
    let phi: Vec<f64> = used.par_iter().map(|&k| fed[k].phase_err_rad.unwrap_or(0.0)).collect();
    // φ_a at true time t_k comes from the IMU at stamp t_k + τ: a shift of +τ/T
    // samples, whole part −reach … reach, taps one before to two after it.
    let reach = reach as isize;
    let sums = LaggedSums::new(&phi_a, &phi, &used, -reach - 1, reach + 2);
    let rss_at = |dtau: f64| rss(&sums.normal_at(dtau / t));
    let grid = ((2.0 * max_abs_s / (0.25 * t)).ceil() as usize).max(8);
    let dtau_s = minimize_1d(-max_abs_s, max_abs_s, grid, 1e-5, rss_at);
    Ok(OffsetProfile { dtau_s })
}

/// The loop with natural frequency scaled by `scale` and, for a 2nd-order
/// loop, damping `zeta` (GNSS-SDR's loops: their bandwidth scaled).
pub(crate) fn scaled_loop(model: &LoopModel, scale: f64, zeta: Option<f64>) -> LoopModel {
    // A new damping at the same ωn first, then every time constant scaled.
    let model = match (*model, zeta) {
        (LoopModel::Kaplan { spec: LoopSpec::SecondOrder { bn_hz, zeta: z0 }, interval_s }, Some(z)) => {
            let wn = gsens_core::second_order_wn_from_bn(bn_hz, z0);
            LoopModel::kaplan(
                LoopSpec::SecondOrder { bn_hz: gsens_core::second_order_bn_from_wn(wn, z), zeta: z },
                interval_s,
            )
        }
        (m, _) => m,
    };
    model.with_bn_scaled(scale)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_distr::{Distribution, Uniform};

    /// The batch pass on pools of 1, 2, 4 and 5 threads is the calibrator
    /// fed epoch by epoch (the model's input prefiltered as a whole), bit
    /// for bit: several blocks and a short last one, gaps, a loop lifted over
    /// 25 updates and one at the log rate.
    #[test]
    fn batch_pass_is_feed_on_any_pool() {
        use gsens_core::{LoggedPhase, LoopModel};
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(8);
        let uniform = Uniform::new(-1.0, 1.0).expect("a range");
        let n = 3 * BATCH_BLOCK_EPOCHS + 123;
        let t_s: Vec<f64> = (0..n).map(|k| k as f64 * 0.025).collect();
        let accel: Vec<[f64; 3]> =
            t_s.iter().map(|t| [(5.7 * t).sin(), 0.3 * uniform.sample(&mut rng), 9.8 + (3.1 * t).cos()]).collect();
        let phase: Vec<Option<f64>> = (0..n)
            .map(|k| {
                let gap = (4090..4100).contains(&k) || k == 9000 || k + 1 == n;
                (!gap).then(|| 0.1 * uniform.sample(&mut rng))
            })
            .collect();
        let series = EpochSeries::without_offset(0.025, &t_s, &phase, &accel);
        let fed_bits = |fed: &[FedEpoch]| -> Vec<([u64; 3], Option<u64>, bool)> {
            fed.iter().map(|e| (e.phi_a.map(f64::to_bits), e.phase_err_rad.map(f64::to_bits), e.used)).collect()
        };
        let ne_bits =
            |ne: &NormalEquations| (ne.ata.map(f64::to_bits), ne.atb.map(f64::to_bits), ne.btb.to_bits(), ne.n);
        for interval_s in [Some(0.001), None] {
            let mut settings = EstimateSettings::default().with_loop(LoopModel::kaplan(LoopSpec::PAPER, interval_s));
            settings.logged_phase = LoggedPhase::Mean;
            let model = build_model(0.025, &settings).unwrap();
            let input = crate::estimate::model_input(&accel, &model);
            let skip = crate::estimate::warmup_epochs(&settings, 0.025);
            let mut cal = Calibrator::new(model, BatchLeastSquares::new(), skip, settings.highpass_hz, 0.025);
            let want: Vec<FedEpoch> = input.iter().zip(&phase).map(|(a, p)| cal.feed(a, *p)).collect();
            assert!(want.iter().filter(|e| e.used).count() > n / 2);
            for threads in [1, 2, 4, 5] {
                let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
                let (fed, ne) = pool.install(|| batch_pass(&series, &settings)).unwrap();
                assert_eq!(fed_bits(&fed), fed_bits(&want), "{threads} threads, loop every {interval_s:?} s");
                assert_eq!(ne_bits(&ne), ne_bits(cal.estimator().normal_equations()), "{threads} threads");
            }
        }
    }

    /// The lagged sums' normal equations against the definition: every used
    /// epoch's φ_a interpolated by Catmull–Rom at the shift and summed.
    #[test]
    fn lagged_sums_give_the_interpolated_normal_equations() {
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(15);
        let uniform = Uniform::new(-1.0, 1.0).expect("a range");
        let n = 600;
        let reach = 7usize;
        let phi_a: Vec<[f64; 3]> = (0..n).map(|_| [0, 1, 2].map(|_| uniform.sample(&mut rng))).collect();
        let margin = reach + 2;
        let used: Vec<usize> = (margin..n - margin).filter(|_| uniform.sample(&mut rng) < 0.6).collect();
        let phi: Vec<f64> = used.iter().map(|_| uniform.sample(&mut rng)).collect();
        let sums = LaggedSums::new(&phi_a, &phi, &used, -(reach as isize) - 1, reach as isize + 2);
        for shift in [-7.0, -6.3, -0.5, 0.0, 1e-9, 0.25, 3.999, 6.75, 7.0] {
            let mut want = NormalEquations::default();
            for (&k, &p) in used.iter().zip(&phi) {
                want.add(p, &catmull_rom(&phi_a, k as f64 + shift));
            }
            let got = sums.normal_at(shift);
            assert_eq!(got.n, want.n);
            assert!((got.btb - want.btb).abs() <= 1e-12 * want.btb, "shift {shift}");
            for r in 0..3 {
                assert!((got.atb[r] - want.atb[r]).abs() <= 1e-12 * want.btb, "shift {shift}: atb[{r}]");
                for q in 0..3 {
                    let (g, w) = (got.ata[(r, q)], want.ata[(r, q)]);
                    assert!((g - w).abs() <= 1e-12 * want.ata.trace(), "shift {shift}: ata[{r}][{q}] {g} vs {w}");
                }
            }
        }
    }

    /// A fixed shift applied at every epoch against the point-by-point
    /// interpolation, edges (clamped) included.
    #[test]
    fn shift_is_catmull_rom_at_every_epoch() {
        let y: Vec<[f64; 3]> = (0..40).map(|i| [(0.3 * i as f64).sin(), (i as f64).sqrt(), -(i as f64)]).collect();
        for s in [-3.25, -1.0, -0.001, 0.0, 0.4, 2.999, 5.5] {
            let by = Shift::samples(s);
            for k in 0..y.len() {
                let (got, want) = (by.at(y.len(), k, |j| y[j]), catmull_rom(&y, k as f64 + s));
                for c in 0..3 {
                    assert!(
                        (got[c] - want[c]).abs() <= 1e-12 * (1.0 + want[c].abs()),
                        "s {s} k {k}: {got:?} vs {want:?}"
                    );
                }
            }
        }
    }

    /// Catmull–Rom passes through the samples and is exact on cubics' lower
    /// relatives: a quadratic is reproduced anywhere between its samples.
    #[test]
    fn catmull_rom_weights_interpolate_and_reproduce_quadratics() {
        for u in [0.0, 0.1, 0.5, 0.9] {
            let w = catmull_rom_weights(u);
            assert!((w.iter().sum::<f64>() - 1.0).abs() < 1e-15);
            let q = |x: f64| 0.3 * x * x - 1.7 * x + 2.0;
            let y: Vec<[f64; 3]> = (0..6).map(|i| [q(i as f64); 3]).collect();
            let got = catmull_rom(&y, 2.0 + u)[0];
            assert!((got - q(2.0 + u)).abs() < 1e-12, "u {u}: {got} vs {}", q(2.0 + u));
        }
        assert_eq!(catmull_rom_weights(0.0), [0.0, 1.0, 0.0, 0.0]);
    }
}
