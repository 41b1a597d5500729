//! The one loop abstraction: a receiver's carrier loop as gsens models it.
//!
//! A [`LoopModel`] answers every question gsens asks about a loop — its
//! response L(j2πf) = φ/Δf, the peak of |L| and the shaking period it
//! implies, the half-power band, the equivalent continuous filter
//! coefficients, stability — and builds the runnable model
//! ([`ModelLoop`]) the regressor triad steps. The regressors, the verdicts,
//! `gsens response`, Fig. 3 and the shaking advice all ask the same object,
//! so a session is described everywhere by the loop that produced it
//! (`docs/conventions.md#loop-models`).

use crate::math::{TAU, exp, ln, round, sqrt};
use crate::pll::gnss_sdr::{A2, A3, B3, BN_OVER_WN_ORDER2, BN_OVER_WN_ORDER3, GnssSdrPll, GnssSdrStage};
use crate::pll::pocket_sdr::{PocketSdrPll, PocketSdrStage};
use crate::pll::{Complex, DiscretePll, LoopError, LoopFilterCoeffs, LoopSpec, ModelLoop};
use crate::units::Decimal;

/// Lowest frequency searched for the peak of |L| \[Hz\].
const SEARCH_LO_HZ: f64 = 1e-3;
/// Highest frequency searched for the peak of |L| (below Nyquist) \[Hz\].
const SEARCH_HI_HZ: f64 = 1e3;
/// Lowest frequency searched for the lower half-power edge \[Hz\].
const BAND_LO_HZ: f64 = 1e-4;

/// A receiver's carrier loop: which implementation, its filter and how often
/// it is updated.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(tag = "implementation", rename_all = "snake_case"))]
#[non_exhaustive]
pub enum LoopModel {
    /// The loop of [`DiscretePll`]'s docs (Kaplan & Hegarty's filter,
    /// integrators clocked once per update) with the filter of `spec`,
    /// updated every `interval_s` seconds (`None`: the continuous-time limit).
    Kaplan {
        /// The loop filter.
        spec: LoopSpec,
        /// Update interval T \[s\]; `None` = continuous time.
        interval_s: Option<f64>,
    },
    /// GNSS-SDR's `dll_pll_veml` carrier loop after bit synchronization,
    /// exactly ([`crate::pll::gnss_sdr`]).
    GnssSdr(GnssSdrStage),
    /// PocketSDR's `pocket_trk` carrier loop after its FLL pull-in, exactly
    /// ([`crate::pll::pocket_sdr`]).
    PocketSdr(PocketSdrStage),
}

/// Which receiver's discrete loop a [`LoopModel`] is: the variants' names,
/// for a user who knows the implementation but states the loop in words.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "snake_case"))]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
pub enum LoopImplementation {
    /// Kaplan & Hegarty's filter as [`DiscretePll`] runs it (gsens's own
    /// loop, the one its simulator tracks with).
    Kaplan,
    /// GNSS-SDR's `dll_pll_veml` carrier loop.
    GnssSdr,
    /// PocketSDR's `pocket_trk` PLL.
    PocketSdr,
}

impl core::fmt::Display for LoopImplementation {
    /// The receiver's name: `Kaplan (gsens)`, `GNSS-SDR`, `PocketSDR`.
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            LoopImplementation::Kaplan => "Kaplan (gsens)",
            LoopImplementation::GnssSdr => "GNSS-SDR",
            LoopImplementation::PocketSdr => "PocketSDR",
        })
    }
}

/// The peak of |L(j2πf)|: where shaking makes the largest phase error per Hz
/// of frequency bias.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct LoopPeak {
    /// Frequency of the peak \[Hz\].
    pub f_hz: f64,
    /// |L| there \[rad/Hz\].
    pub rad_per_hz: f64,
}

/// The two shaking rates of the two-rate protocol, as multiples of the
/// loop's peak frequency: one below the peak, where |L| grows with the
/// frequency and a loop error changes the response's magnitude most, one
/// above it, where |L| falls and barely depends on the loop's natural
/// frequency. A 2nd-order loop (ζ = 1/√2) keeps 89 % and 82 % of its peak
/// sensitivity there (|L(u)|/|L(1)| = 2ζu/√((1 − u²)² + 4ζ²u²)), while Γ
/// scales both rates alike and an IMU time offset turns both phases: the
/// ratio of the two responses measures the loop, which one rate confounds
/// with the offset.
pub const TWO_RATE_FACTORS: [f64; 2] = [0.7, 1.6];

impl LoopPeak {
    /// The shaking period that excites the loop most, 1/f_peak \[s\].
    pub fn period_s(&self) -> f64 {
        1.0 / self.f_hz
    }

    /// The periods of the two-rate protocol, slow then fast:
    /// 1/(k·f_peak) for k in [`TWO_RATE_FACTORS`] \[s\].
    pub fn two_rate_periods_s(&self) -> [f64; 2] {
        TWO_RATE_FACTORS.map(|k| 1.0 / (k * self.f_hz))
    }
}

impl LoopModel {
    /// The loop of `spec` updated every `interval_s` seconds (`None`:
    /// continuous time).
    pub fn kaplan(spec: LoopSpec, interval_s: Option<f64>) -> Self {
        LoopModel::Kaplan { spec, interval_s }
    }

    /// The same loop updated every `interval_s` when no interval was given
    /// (a log's interval stands in for an unstated loop interval).
    pub fn with_default_interval(self, interval_s: f64) -> Self {
        match self {
            LoopModel::Kaplan { spec, interval_s: None } => LoopModel::Kaplan { spec, interval_s: Some(interval_s) },
            other => other,
        }
    }

    /// The loop update interval T \[s\] (`None`: continuous time).
    pub fn interval_s(&self) -> Option<f64> {
        match self {
            LoopModel::Kaplan { interval_s, .. } => *interval_s,
            LoopModel::GnssSdr(stage) => Some(stage.interval_s()),
            LoopModel::PocketSdr(stage) => Some(stage.interval_s),
        }
    }

    /// The Nyquist frequency of the update rate, 1/(2T) \[Hz\] (`None`:
    /// continuous time).
    pub fn nyquist_hz(&self) -> Option<f64> {
        self.interval_s().map(|t| 0.5 / t)
    }

    /// The equivalent continuous loop filter F(s) = c0 + c1/s + c2/s²,
    /// checked for stability of the continuous loop (Routh–Hurwitz).
    ///
    /// For GNSS-SDR's loops (module docs of [`crate::pll::gnss_sdr`]): order 2,
    /// ωn = Bn/0.53, F = 1.414·ωn + ωn²/s; order 3, ωn = Bn/0.7845,
    /// F = 2.4·ωn + 0.55·ωn²/s + 0.25·ωn³/s². For PocketSDR's, Kaplan's
    /// F = 2.4·ω + 1.1·ω²/s + ω³/s², ω = b_pll/0.7845.
    pub fn coeffs(&self) -> Result<LoopFilterCoeffs, LoopError> {
        match self {
            LoopModel::Kaplan { spec, .. } => spec.coeffs(),
            LoopModel::GnssSdr(stage) => {
                GnssSdrPll::new(*stage)?;
                let c = if stage.order == 3 {
                    let wn = stage.bw_hz / BN_OVER_WN_ORDER3;
                    LoopFilterCoeffs {
                        c0_per_s: B3 * wn,
                        c1_per_s2: 0.5 * A3 * wn * wn,
                        c2_per_s3: 0.25 * wn * wn * wn,
                    }
                } else {
                    let wn = stage.bw_hz / BN_OVER_WN_ORDER2;
                    LoopFilterCoeffs { c0_per_s: A2 * wn, c1_per_s2: wn * wn, c2_per_s3: 0.0 }
                };
                LoopSpec::Coefficients(c).coeffs()
            }
            LoopModel::PocketSdr(stage) => {
                stage.check()?;
                LoopSpec::Coefficients(stage.coeffs()).coeffs()
            }
        }
    }

    /// The filter as a [`LoopSpec`] (GNSS-SDR's as its equivalent coefficients).
    pub fn spec(&self) -> Result<LoopSpec, LoopError> {
        match self {
            LoopModel::Kaplan { spec, .. } => Ok(*spec),
            LoopModel::GnssSdr(_) | LoopModel::PocketSdr(_) => self.coeffs().map(LoopSpec::Coefficients),
        }
    }

    /// Loop order: the number of integrators (2 or 3 for receiver loops).
    pub fn order(&self) -> u8 {
        match self {
            LoopModel::Kaplan { spec, .. } => spec.order(),
            LoopModel::GnssSdr(stage) => stage.order,
            LoopModel::PocketSdr(_) => 3,
        }
    }

    /// The same loop with its noise bandwidth Bn times `scale`, its shape (ζ,
    /// or a3 and b3) and interval kept: every time constant divided by
    /// `scale`, so a loop given by its filter coefficients has c0·s, c1·s²,
    /// c2·s³ (Bn ∝ ωn at a fixed shape).
    pub fn with_bn_scaled(&self, scale: f64) -> LoopModel {
        match *self {
            LoopModel::Kaplan { spec, interval_s } => {
                let spec = match spec {
                    LoopSpec::SecondOrder { bn_hz, zeta } => LoopSpec::SecondOrder { bn_hz: bn_hz * scale, zeta },
                    LoopSpec::ThirdOrder { bn_hz, a3, b3 } => LoopSpec::ThirdOrder { bn_hz: bn_hz * scale, a3, b3 },
                    LoopSpec::Coefficients(c) => LoopSpec::Coefficients(LoopFilterCoeffs {
                        c0_per_s: c.c0_per_s * scale,
                        c1_per_s2: c.c1_per_s2 * scale * scale,
                        c2_per_s3: c.c2_per_s3 * scale * scale * scale,
                    }),
                };
                LoopModel::Kaplan { spec, interval_s }
            }
            LoopModel::GnssSdr(stage) => LoopModel::GnssSdr(GnssSdrStage { bw_hz: stage.bw_hz * scale, ..stage }),
            LoopModel::PocketSdr(stage) => LoopModel::PocketSdr(PocketSdrStage { bw_hz: stage.bw_hz * scale, ..stage }),
        }
    }

    /// The nominal noise bandwidth Bn \[Hz\] where the loop is specified by it.
    pub fn bn_hz(&self) -> Option<f64> {
        match self {
            LoopModel::Kaplan {
                spec: LoopSpec::SecondOrder { bn_hz, .. } | LoopSpec::ThirdOrder { bn_hz, .. },
                ..
            } => Some(*bn_hz),
            LoopModel::Kaplan { .. } => None,
            LoopModel::GnssSdr(stage) => Some(stage.bw_hz),
            LoopModel::PocketSdr(stage) => Some(stage.bw_hz),
        }
    }

    /// Natural frequency ωn/2π \[Hz\]: of the specification, or c2^(1/3)
    /// (c1^(1/2) without a second integrator) of the filter coefficients.
    pub fn natural_frequency_hz(&self) -> Option<f64> {
        let wn = match self {
            LoopModel::Kaplan { spec, .. } => spec.wn_rad_per_s(),
            LoopModel::GnssSdr(_) | LoopModel::PocketSdr(_) => {
                self.coeffs().ok().and_then(|c| LoopSpec::Coefficients(c).wn_rad_per_s())
            }
        };
        wn.map(|w| w / TAU)
    }

    /// Checks the loop: a valid, stable continuous filter and, when updated
    /// every T, a stable discrete loop at T (roots of its characteristic
    /// polynomial, or the eigenvalues of GNSS-SDR's one-record transition, or
    /// the roots of PocketSDR's characteristic polynomial).
    pub fn check(&self) -> Result<(), LoopError> {
        match self {
            LoopModel::Kaplan { spec, interval_s } => {
                let c = spec.coeffs()?;
                match interval_s {
                    Some(t) if !c.is_stable_at(*t) => Err(LoopError::UnstableAtInterval),
                    _ => Ok(()),
                }
            }
            LoopModel::GnssSdr(stage) => {
                if GnssSdrPll::new(*stage)?.is_stable() {
                    Ok(())
                } else {
                    Err(LoopError::UnstableAtInterval)
                }
            }
            LoopModel::PocketSdr(stage) => {
                stage.check()?;
                if stage.is_stable() { Ok(()) } else { Err(LoopError::UnstableAtInterval) }
            }
        }
    }

    /// The response L = φ/Δf at `f_hz` \[rad/Hz\]: the discrete loop's
    /// L_d(e^{j2πfT}) when updated every T ([`LoopFilterCoeffs::response_discrete`],
    /// [`GnssSdrPll::response`], [`PocketSdrStage::response`]), else the continuous −2π/(s + F(s)) at
    /// s = j2πf. Zero for an invalid loop (call [`LoopModel::check`] first).
    pub fn response(&self, f_hz: f64) -> Complex<f64> {
        match self {
            LoopModel::Kaplan { spec, interval_s } => match (spec.coeffs(), interval_s) {
                (Ok(c), Some(t)) => c.response_discrete(f_hz, *t),
                (Ok(c), None) => c.response_continuous(f_hz),
                (Err(_), _) => Complex::new(0.0, 0.0),
            },
            LoopModel::GnssSdr(stage) => match GnssSdrPll::new(*stage) {
                Ok(p) => p.response(f_hz),
                Err(_) => Complex::new(0.0, 0.0),
            },
            LoopModel::PocketSdr(stage) => match stage.check() {
                Ok(()) => stage.response(f_hz),
                Err(_) => Complex::new(0.0, 0.0),
            },
        }
    }

    /// |L| \[rad/Hz\].
    pub fn magnitude(&self, f_hz: f64) -> f64 {
        sqrt(self.response(f_hz).norm_sqr())
    }

    /// Highest frequency the response is searched to: 1 kHz or just below Nyquist.
    fn search_hi_hz(&self) -> f64 {
        self.nyquist_hz().map_or(SEARCH_HI_HZ, |n| (0.999 * n).min(SEARCH_HI_HZ))
    }

    /// The peak of |L| by golden-section search on a log-frequency axis from
    /// 1 mHz to 1 kHz (or just below Nyquist). |L| = 2π·|s|²/|s³ + c0s² + c1s + c2|
    /// rises as f (2nd order) or f² (3rd order), falls as 1/f and is unimodal
    /// between for the stable loops gsens models. For a 2nd-order continuous loop the peak is at ωn with
    /// |L| = π/(ζ·ωn) (conventions, `docs/conventions.md#loop-models`).
    pub fn peak(&self) -> Result<LoopPeak, LoopError> {
        self.check()?;
        let mag = |lf: f64| self.magnitude(exp(lf));
        let (mut a, mut b) = (ln(SEARCH_LO_HZ), ln(self.search_hi_hz()));
        let r = (sqrt(5.0) - 1.0) / 2.0;
        for _ in 0..100 {
            let x1 = b - r * (b - a);
            let x2 = a + r * (b - a);
            if mag(x1) > mag(x2) {
                b = x2;
            } else {
                a = x1;
            }
        }
        let f_hz = exp(0.5 * (a + b));
        Ok(LoopPeak { f_hz, rad_per_hz: self.magnitude(f_hz) })
    }

    /// Where |L| falls to peak/√2 on either side of the peak \[Hz\]
    /// (bisection on a log axis): shaking inside this band gets at least half
    /// of the loop's peak power sensitivity.
    pub fn half_power_band_hz(&self) -> Result<[f64; 2], LoopError> {
        let peak = self.peak()?;
        let target = peak.rad_per_hz / sqrt(2.0);
        let find = |mut lo: f64, mut hi: f64, rising: bool| {
            for _ in 0..100 {
                let m = sqrt(lo * hi);
                if (self.magnitude(m) > target) == rising {
                    hi = m;
                } else {
                    lo = m;
                }
            }
            sqrt(lo * hi)
        };
        Ok([find(BAND_LO_HZ, peak.f_hz, true), find(peak.f_hz, self.search_hi_hz(), false)])
    }

    /// Time for the loop's slowest natural mode to decay by e⁻ⁿ, n =
    /// `time_constants` \[s\]: `n·T/(−ln ρ)`, ρ the largest modulus of the
    /// discrete loop's poles ([`LoopFilterCoeffs::spectral_radius_at`],
    /// [`GnssSdrPll::settling_time_s`], [`PocketSdrStage::settling_time_s`]), T
    /// the update interval. Infinite for a loop that cannot run (no interval,
    /// unstable).
    pub fn settling_time_s(&self, time_constants: f64) -> f64 {
        match self {
            LoopModel::Kaplan { spec, interval_s: Some(t) } => {
                let rho = spec.coeffs().ok().and_then(|c| c.spectral_radius_at(*t));
                crate::pll::settling_time_s(rho, *t, time_constants)
            }
            LoopModel::Kaplan { interval_s: None, .. } => f64::INFINITY,
            LoopModel::GnssSdr(stage) => {
                GnssSdrPll::new(*stage).map_or(f64::INFINITY, |p| p.settling_time_s(time_constants))
            }
            LoopModel::PocketSdr(stage) => stage.settling_time_s(time_constants),
        }
    }

    /// Which receiver's loop this is.
    pub fn implementation(&self) -> LoopImplementation {
        match self {
            LoopModel::Kaplan { .. } => LoopImplementation::Kaplan,
            LoopModel::GnssSdr(_) => LoopImplementation::GnssSdr,
            LoopModel::PocketSdr(_) => LoopImplementation::PocketSdr,
        }
    }

    /// The discrete loops a loop given in words (order, Bn, shape and update
    /// interval, as [`LoopModel::Kaplan`]) may be, the loop itself first:
    /// the same words name different filters in different receivers.
    ///
    /// - Kaplan & Hegarty's filter as [`DiscretePll`] runs it (this loop);
    /// - GNSS-SDR's `dll_pll_veml` ([`crate::pll::gnss_sdr`]) with bandwidth
    ///   Bn, for a 2nd-order loop of ζ = 0.707 (its a₂ = 1.414) or a
    ///   3rd-order one of Kaplan's a₃, b₃ (the values GNSS-SDR names), when
    ///   the interval is a whole number of 1 ms code periods that divides the
    ///   20 ms data bit (its `extend_correlation_symbols`);
    /// - PocketSDR's `pocket_trk` PLL ([`crate::pll::pocket_sdr`]) with
    ///   `b_pll` = Bn, for a 3rd-order loop of Kaplan's a₃, b₃.
    ///
    /// Only the forms that are stable at the interval are given. A loop
    /// that is already a receiver's own, or given by its filter coefficients
    /// or without an interval, has only itself.
    pub fn discrete_forms(&self) -> impl Iterator<Item = LoopModel> {
        // ζ and a₃, b₃ as GNSS-SDR and PocketSDR write them (to their digits).
        let near = |a: f64, b: f64| (a - b).abs() <= 5e-4;
        let (gnss_sdr, pocket_sdr) = match *self {
            LoopModel::Kaplan { spec, interval_s: Some(t) } => {
                let kaplan_third =
                    |a3: f64, b3: f64| near(a3, crate::pll::KAPLAN_A3) && near(b3, crate::pll::KAPLAN_B3);
                let (order, bn_hz) = match spec {
                    LoopSpec::SecondOrder { bn_hz, zeta } if near(zeta, 0.5 * A2) => (Some(2), bn_hz),
                    LoopSpec::ThirdOrder { bn_hz, a3, b3 } if kaplan_third(a3, b3) => (Some(3), bn_hz),
                    _ => (None, 0.0),
                };
                let symbols = round(t / crate::pll::gnss_sdr::SYMBOL_S);
                let whole_ms = symbols >= 1.0 && (t - symbols * crate::pll::gnss_sdr::SYMBOL_S).abs() <= 1e-9 * t;
                let gnss_sdr = order
                    .filter(|_| whole_ms)
                    .map(|order| GnssSdrStage { order, bw_hz: bn_hz, symbols: symbols as u32 })
                    .filter(|stage| stage.updates_per_record().is_some())
                    .map(LoopModel::GnssSdr);
                let pocket_sdr =
                    (order == Some(3)).then_some(LoopModel::PocketSdr(PocketSdrStage { bw_hz: bn_hz, interval_s: t }));
                (gnss_sdr, pocket_sdr)
            }
            _ => (None, None),
        };
        // The receivers' forms only where they are stable at the interval.
        let others = gnss_sdr.into_iter().chain(pocket_sdr).filter(|m| m.check().is_ok());
        core::iter::once(*self).chain(others)
    }

    /// The runnable linear model Δf → φ, one loop update per step (what the
    /// regressor triad runs three of). Needs an update interval; checks the loop.
    pub fn runnable(&self) -> Result<ModelLoop, LoopError> {
        self.check()?;
        match self {
            LoopModel::Kaplan { spec, interval_s: Some(t) } => Ok(DiscretePll::new(spec.coeffs()?, *t).into()),
            LoopModel::Kaplan { interval_s: None, .. } => Err(LoopError::NonPositiveParameter("interval_s")),
            LoopModel::GnssSdr(stage) => Ok(GnssSdrPll::new(*stage)?.into()),
            LoopModel::PocketSdr(stage) => Ok(PocketSdrPll::new(*stage)?.into()),
        }
    }
}

impl core::fmt::Display for LoopModel {
    /// The loop in words, e.g. `2nd order, Bn 3 Hz, ζ 0.707, ωn/2π 0.900 Hz,
    /// updated every 0.001 s`.
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        let nat = |f: &mut core::fmt::Formatter<'_>| match self.natural_frequency_hz() {
            Some(fn_hz) => write!(f, ", ωn/2π {fn_hz:.3} Hz"),
            None => Ok(()),
        };
        match self {
            LoopModel::Kaplan { spec, interval_s } => {
                match *spec {
                    LoopSpec::SecondOrder { bn_hz, zeta } => {
                        write!(f, "2nd order, Bn {} Hz, ζ {zeta:.3}", Short(bn_hz))?
                    }
                    LoopSpec::ThirdOrder { bn_hz, a3, b3 } => {
                        write!(f, "3rd order, Bn {} Hz, a3 {a3}, b3 {b3}", Short(bn_hz))?
                    }
                    LoopSpec::Coefficients(c) => write!(
                        f,
                        "filter c0 {} /s, c1 {} /s², c2 {} /s³",
                        Decimal(c.c0_per_s),
                        Decimal(c.c1_per_s2),
                        Decimal(c.c2_per_s3)
                    )?,
                }
                nat(f)?;
                match interval_s {
                    Some(t) => write!(f, ", updated every {} s", Decimal(*t)),
                    None => write!(f, ", continuous"),
                }
            }
            LoopModel::GnssSdr(stage) => {
                write!(
                    f,
                    "GNSS-SDR dll_pll_veml, order {}, Bn {} Hz, {} ms integrations",
                    stage.order,
                    Decimal(stage.bw_hz),
                    stage.symbols
                )?;
                nat(f)
            }
            LoopModel::PocketSdr(stage) => {
                write!(
                    f,
                    "PocketSDR pocket_trk PLL, 3rd order, b_pll {} Hz, {} ms updates",
                    Short(stage.bw_hz),
                    Decimal(stage.interval_s * 1e3)
                )?;
                nat(f)
            }
        }
    }
}

/// A value with at most four decimals and no trailing zeros (3 → `3`,
/// 2.976367 → `2.9764`): a fitted bandwidth reads like a stated one.
struct Short(f64);

impl core::fmt::Display for Short {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        let r = round(self.0 * 1e4) / 1e4;
        if r == self.0 || !r.is_finite() { write!(f, "{}", self.0) } else { write!(f, "{r}") }
    }
}
