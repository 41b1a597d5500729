//! The joint fit's parameters: which are fitted, where each sits in the
//! solver's vector, and the nuisance parameters' steps and limits.

/// Which parameters a joint fit estimates: Γ on `axes` of its axes, and the
/// nuisance parameters asked for. The solver's vector (and the rows and
/// columns of its covariance) holds Γ on those axes first, then ln s, ζ and
/// τ, each only when fitted, in this order.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Fitted {
    /// How many axes of Γ are in the fit.
    pub axes: usize,
    /// ln s, the scale of the stated loop's natural frequency.
    pub natural_frequency: bool,
    /// ζ, a 2nd-order loop's damping.
    pub damping: bool,
    /// τ, the IMU time offset \[s\], within ± this of the series' own.
    pub offset_max_abs_s: Option<f64>,
}

impl Fitted {
    /// The number of parameters, the length of the solver's vector.
    pub(super) fn len(&self) -> usize {
        self.axes + usize::from(self.natural_frequency) + usize::from(self.damping) + usize::from(self.offset())
    }

    /// Whether any nuisance parameter is fitted (besides Γ).
    pub(super) fn any_nuisance(&self) -> bool {
        self.len() > self.axes
    }

    fn offset(&self) -> bool {
        self.offset_max_abs_s.is_some()
    }

    /// The index of ln s in the solver's vector, when fitted.
    pub(super) fn loop_index(&self) -> Option<usize> {
        self.natural_frequency.then_some(self.axes)
    }

    /// The index of ζ, when fitted.
    pub(super) fn zeta_index(&self) -> Option<usize> {
        self.damping.then_some(self.axes + usize::from(self.natural_frequency))
    }

    /// The index of τ, when fitted.
    pub(super) fn tau_index(&self) -> Option<usize> {
        self.offset().then_some(self.axes + usize::from(self.natural_frequency) + usize::from(self.damping))
    }

    /// `v`, a vector laid out as the solver's, as named parameters.
    pub(super) fn read(&self, v: &[f64]) -> Params {
        debug_assert_eq!(v.len(), self.len());
        Params {
            gamma: v[..self.axes].to_vec(),
            ln_s: self.loop_index().map(|i| v[i]),
            zeta: self.zeta_index().map(|i| v[i]),
            tau_s: self.tau_index().map(|i| v[i]),
        }
    }
}

/// Values (or steps) of the joint fit's parameters, named: Γ on the fit's
/// axes \[Hz/(m/s²)\], ln s, ζ and τ \[s\] (`None`: not fitted).
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Params {
    pub gamma: Vec<f64>,
    pub ln_s: Option<f64>,
    pub zeta: Option<f64>,
    pub tau_s: Option<f64>,
}

impl Params {
    /// The parameters laid out as the solver's vector ([`Fitted::read`]'s inverse).
    #[cfg(test)]
    pub(super) fn to_vec(&self) -> Vec<f64> {
        let nuisance = [self.ln_s, self.zeta, self.tau_s].into_iter().flatten();
        self.gamma.iter().copied().chain(nuisance).collect()
    }

    /// The nuisance parameters' (index in the solver's vector, value), in order.
    pub(super) fn nuisance(&self, fitted: &Fitted) -> Vec<(usize, f64)> {
        [(fitted.loop_index(), self.ln_s), (fitted.zeta_index(), self.zeta), (fitted.tau_index(), self.tau_s)]
            .into_iter()
            .filter_map(|(i, v)| i.zip(v))
            .collect()
    }
}

/// Where a joint fit's Gauss–Newton starts.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum Start {
    /// The stated loop, at the offset of the global search under it.
    Search,
    /// The stated loop, at this offset \[s\].
    Offset(f64),
    /// Where an earlier fit of the same problem (loop, settings, axes)
    /// ended: Gauss–Newton then takes one step to confirm it.
    At(Theta),
}

/// Where the nuisance parameters θ are: ln s of the loop (relative to the
/// loop the fit starts from), its damping ζ (the stated one's when not
/// fitted; `None` for a loop without one) and the offset τ \[s\] (relative to
/// the series' own).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Theta {
    pub ln_s: f64,
    pub zeta: Option<f64>,
    pub dtau_s: f64,
}

impl Theta {
    /// The largest Gauss–Newton step of ln s: a loop 35 % off per step.
    pub(super) const MAX_LN_S_STEP: f64 = 0.3;
    /// ln s stays within ± this (natural frequencies 0.22–4.5 times the stated).
    pub(super) const LN_S_LIMIT: f64 = 1.5;
    /// The largest step of ζ.
    pub(super) const MAX_ZETA_STEP: f64 = 0.2;
    /// ζ stays within these.
    pub(super) const ZETA_LIMITS: [f64; 2] = [0.25, 2.0];
    /// The largest step of τ, as a fraction of its range ±max.
    pub(super) const MAX_TAU_STEP_FRACTION: f64 = 0.25;

    /// A solver's nuisance step limited: ln s to ±[`Self::MAX_LN_S_STEP`], ζ to
    /// ±[`Self::MAX_ZETA_STEP`], τ to ±[`Self::MAX_TAU_STEP_FRACTION`] of its range
    /// `offset_max_abs_s` (Γ as given).
    pub(super) fn limited_step(step: &Params, offset_max_abs_s: Option<f64>) -> Params {
        Params {
            gamma: step.gamma.clone(),
            ln_s: step.ln_s.map(|d| d.clamp(-Self::MAX_LN_S_STEP, Self::MAX_LN_S_STEP)),
            zeta: step.zeta.map(|d| d.clamp(-Self::MAX_ZETA_STEP, Self::MAX_ZETA_STEP)),
            tau_s: step.tau_s.zip(offset_max_abs_s).map(|(d, max)| {
                let m = Self::MAX_TAU_STEP_FRACTION * max;
                d.clamp(-m, m)
            }),
        }
    }

    /// θ moved by the nuisance part of `step` (limited already), each
    /// parameter kept within its limits: ln s within ±[`Self::LN_S_LIMIT`], ζ
    /// within [`Self::ZETA_LIMITS`], τ within ±`offset_max_abs_s`.
    pub(super) fn advanced(&self, step: &Params, offset_max_abs_s: Option<f64>) -> Theta {
        let [zeta_lo, zeta_hi] = Self::ZETA_LIMITS;
        Theta {
            ln_s: step.ln_s.map_or(self.ln_s, |d| (self.ln_s + d).clamp(-Self::LN_S_LIMIT, Self::LN_S_LIMIT)),
            zeta: match step.zeta {
                Some(d) => self.zeta.map(|z| (z + d).clamp(zeta_lo, zeta_hi)),
                None => self.zeta,
            },
            dtau_s: match (step.tau_s, offset_max_abs_s) {
                (Some(d), Some(max)) => (self.dtau_s + d).clamp(-max, max),
                _ => self.dtau_s,
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const ALL: Fitted = Fitted { axes: 2, natural_frequency: true, damping: true, offset_max_abs_s: Some(0.1) };

    #[test]
    fn the_layout_is_gamma_then_the_nuisance_parameters_fitted() {
        assert_eq!((ALL.len(), ALL.loop_index(), ALL.zeta_index(), ALL.tau_index()), (5, Some(2), Some(3), Some(4)));
        let no_zeta = Fitted { axes: 3, damping: false, ..ALL };
        assert_eq!(
            (no_zeta.len(), no_zeta.loop_index(), no_zeta.zeta_index(), no_zeta.tau_index()),
            (5, Some(3), None, Some(4))
        );
        let offset_only = Fitted { natural_frequency: false, damping: false, ..ALL };
        assert_eq!((offset_only.loop_index(), offset_only.tau_index()), (None, Some(2)));
        let gamma_only = Fitted { offset_max_abs_s: None, ..offset_only };
        assert_eq!((gamma_only.len(), gamma_only.any_nuisance(), gamma_only.tau_index()), (2, false, None));
    }

    #[test]
    fn the_solvers_vector_round_trips() {
        let v = [0.09, -0.08, 0.01, 0.02, -0.003];
        let p = ALL.read(&v);
        assert_eq!(p, Params { gamma: vec![0.09, -0.08], ln_s: Some(0.01), zeta: Some(0.02), tau_s: Some(-0.003) });
        assert_eq!(p.to_vec(), v);
        assert_eq!(p.nuisance(&ALL), [(2, 0.01), (3, 0.02), (4, -0.003)]);
        let loop_and_offset = Fitted { damping: false, ..ALL };
        let v = [1.0, 2.0, 3.0, 4.0];
        let p = loop_and_offset.read(&v);
        assert_eq!((p.ln_s, p.zeta, p.tau_s), (Some(3.0), None, Some(4.0)));
        assert_eq!((p.to_vec(), p.nuisance(&loop_and_offset)), (v.to_vec(), vec![(2, 3.0), (3, 4.0)]));
    }

    #[test]
    fn steps_and_parameters_stay_within_their_limits() {
        let big = Params { gamma: vec![7.0], ln_s: Some(1.0), zeta: Some(-0.5), tau_s: Some(0.05) };
        let step = Theta::limited_step(&big, Some(0.1));
        assert_eq!(step, Params { gamma: vec![7.0], ln_s: Some(0.3), zeta: Some(-0.2), tau_s: Some(0.025) });
        let small = Params { gamma: vec![], ln_s: Some(-0.0078125), zeta: Some(0.0625), tau_s: Some(-0.0009765625) };
        assert_eq!(Theta::limited_step(&small, Some(0.1)), small);

        let at_edges = Theta { ln_s: 1.4, zeta: Some(0.3), dtau_s: 0.09 };
        let moved = at_edges.advanced(&step, Some(0.1));
        assert_eq!(moved, Theta { ln_s: 1.5, zeta: Some(0.25), dtau_s: 0.1 });
        let inside = Theta { ln_s: 0.5, zeta: Some(0.75), dtau_s: 0.0 }.advanced(&small, Some(0.1));
        assert_eq!(inside, Theta { ln_s: 0.4921875, zeta: Some(0.8125), dtau_s: -0.0009765625 });
        // What is not fitted does not move.
        let none = Params { gamma: vec![], ln_s: None, zeta: None, tau_s: None };
        assert_eq!(at_edges.advanced(&none, None), at_edges);
        let no_damping = Theta { zeta: None, ..at_edges }.advanced(&step, Some(0.1));
        assert_eq!(no_damping.zeta, None);
    }
}
