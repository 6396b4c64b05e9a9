//! The values of the §9.1 terms in a simulation: by code name, checked, described for messages.

use super::super::on_x::{smoothing_key, OnXValues};
use crate::bouc_wen::BoucWen;
use crate::error::{finite, CoreError, Result};
use crate::terms::{
    check_asymmetry, check_coulomb_smoothing, parse_placed, Place, TermKind, COULOMB_SMOOTHING,
    COULOMB_SMOOTHING_KEY,
};

/// Parameters of the §9.1 terms; an absent term is 0 (which is also what a zero parameter
/// means physically: `Play(0)` is the identity, `SensorLag(0)` no lag).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TermValues {
    /// Output offset `y0` (units of `y`).
    pub offset: f64,
    /// Parallel stiffness `k` (`[y]/[u]`).
    pub stiffness: f64,
    /// Viscous damping `c` (`[y] s/[u]`).
    pub viscous: f64,
    /// Inertia `m` (`[y] s^2/[u]`).
    pub inertia: f64,
    /// Coulomb friction level `f` (units of `y`).
    pub coulomb: f64,
    /// `eps` of `tanh(udot / (eps Vmax))`, in `(0, 0.5]`.
    pub coulomb_smoothing: f64,
    /// Sensor lag `tau` (s), `>= 0`.
    pub sensor_lag: f64,
    /// Asymmetry `delta` (`1/[w]^mu`), `|delta| < beta + gamma`.
    pub asymmetry: f64,
    /// Play half-width `b` (units of `x`), `>= 0`.
    pub play: f64,
    /// Strength degradation `delta_nu` (`1/([w] [x])`), `>= 0`: Baber-Noori
    /// `nu = 1 + delta_nu e`, `e = int w dxp` (the hysteretic energy dissipated), multiplies the
    /// beta, gamma and delta terms of the rate.
    pub degradation: f64,
    /// Stiffness degradation `delta_eta` (`1/([w] [x])`), `>= 0`: Baber-Noori
    /// `eta = 1 + delta_eta e` divides the whole rate (the same energy state as `degradation`).
    pub stiffness_degradation: f64,
    /// Pinching `zeta1` in `[0, 1)`: the rate times Foliente's `h(w, sgn xpdot)` (module header).
    pub pinching: f64,
    /// Series dashpot `rho` (`[x]/([w] s)`), `>= 0`: the element is driven by its own travel,
    /// `ddot = xpdot - rho w` (module header).
    pub series_dashpot: f64,
    /// The mechanical terms across the hysteretic element, on x (`rust/simulate/on_x.rs`).
    pub on_x: OnXValues,
    /// Dahl friction on u: level `Fc` ([y]), `>= 0` (`with_terms/dahl.rs`).
    pub dahl: f64,
    /// Dahl friction on u: pre-sliding stiffness `sigma` ([y]/[u]), `>= 0`.
    pub dahl_sigma: f64,
    /// Dahl friction on x: level `Fc` ([y]), `>= 0`.
    pub dahl_x: f64,
    /// Dahl friction on x: pre-sliding stiffness `sigma` ([y]/[x]), `>= 0`.
    pub dahl_sigma_x: f64,
}

impl Default for TermValues {
    fn default() -> Self {
        Self {
            offset: 0.0,
            stiffness: 0.0,
            viscous: 0.0,
            inertia: 0.0,
            coulomb: 0.0,
            coulomb_smoothing: COULOMB_SMOOTHING,
            sensor_lag: 0.0,
            asymmetry: 0.0,
            play: 0.0,
            degradation: 0.0,
            stiffness_degradation: 0.0,
            pinching: 0.0,
            series_dashpot: 0.0,
            on_x: OnXValues::default(),
            dahl: 0.0,
            dahl_sigma: 0.0,
            dahl_x: 0.0,
            dahl_sigma_x: 0.0,
        }
    }
}

impl TermValues {
    /// Values from `(code name, value)` pairs (the code names of [`TermKind`] that act in a
    /// simulation, at their usual place or on x as `"<code name>@x"`, and
    /// [`COULOMB_SMOOTHING_KEY`] and the on-x friction's [`smoothing_key`]); missing ones are
    /// absent.
    ///
    /// Errors: [`CoreError::InvalidParameter`] for an unknown name or place, or a term without a
    /// simulation form. Values are checked by [`TermValues::validate`].
    pub fn from_named<'a>(pairs: impl IntoIterator<Item = (&'a str, f64)>) -> Result<Self> {
        let mut t = Self::default();
        let on_x_smoothing = smoothing_key();
        for (name, v) in pairs {
            let slot = if name == COULOMB_SMOOTHING_KEY {
                &mut t.coulomb_smoothing
            } else if name == on_x_smoothing {
                &mut t.on_x.coulomb_smoothing
            } else {
                let (kind, place) = parse_placed(name)?;
                let slot = match place {
                    Place::Usual => t.slot(kind),
                    // `parse_placed` admits only the mechanical terms on x.
                    Place::X => t.slot_on_x(kind),
                };
                slot.ok_or_else(|| {
                    CoreError::InvalidParameter(format!(
                        "term {name:?} has no time-domain form (steady-loop model only); a \
                         simulation takes every other term"
                    ))
                })?
            };
            *slot = v;
        }
        Ok(t)
    }

    /// The value of `kind`, `None` for a term the simulation does not have.
    pub fn get(&self, kind: TermKind) -> Option<f64> {
        let mut t = *self;
        t.slot(kind).map(|v| *v)
    }

    /// Where `kind`'s value is kept, `None` for a term the simulation does not have.
    fn slot(&mut self, kind: TermKind) -> Option<&mut f64> {
        match kind {
            TermKind::Offset => Some(&mut self.offset),
            TermKind::Stiffness => Some(&mut self.stiffness),
            TermKind::Viscous => Some(&mut self.viscous),
            TermKind::Inertia => Some(&mut self.inertia),
            TermKind::Coulomb => Some(&mut self.coulomb),
            TermKind::SensorLag => Some(&mut self.sensor_lag),
            TermKind::Asymmetry => Some(&mut self.asymmetry),
            TermKind::Play => Some(&mut self.play),
            TermKind::Degradation => Some(&mut self.degradation),
            TermKind::StiffnessDegradation => Some(&mut self.stiffness_degradation),
            TermKind::Pinching => Some(&mut self.pinching),
            TermKind::SeriesDashpot => Some(&mut self.series_dashpot),
            TermKind::Dahl => Some(&mut self.dahl),
            TermKind::DahlSigma => Some(&mut self.dahl_sigma),
            // The measured input's own harmonics: simulate takes that input itself.
            TermKind::Distortion => None,
        }
    }

    /// Where `kind`'s value on x is kept: Dahl friction here, the mechanical terms in
    /// [`OnXValues`].
    fn slot_on_x(&mut self, kind: TermKind) -> Option<&mut f64> {
        match kind {
            TermKind::Dahl => Some(&mut self.dahl_x),
            TermKind::DahlSigma => Some(&mut self.dahl_sigma_x),
            _ => self.on_x.slot(kind),
        }
    }

    /// Dahl friction's values on x, `(kind, value)`.
    fn dahl_on_x(&self) -> [(TermKind, f64); 2] {
        [
            (TermKind::Dahl, self.dahl_x),
            (TermKind::DahlSigma, self.dahl_sigma_x),
        ]
    }

    /// Checks the §9.1 admissibility against the hysteresis `bw`: all finite, `tau >= 0`,
    /// `b >= 0`, `delta_nu >= 0`, `0 < eps <= 0.5`, `|delta| < beta + gamma`.
    ///
    /// Errors: [`CoreError::NonFinite`], [`CoreError::InvalidParameter`].
    pub fn validate(&self, bw: &BoucWen) -> Result<()> {
        let values = || {
            TermKind::ALL
                .into_iter()
                .filter_map(|k| self.get(k).map(|v| (k, v)))
        };
        for (kind, v) in values() {
            finite(kind.name(), v)?;
        }
        check_coulomb_smoothing(self.coulomb_smoothing)?;
        for (kind, v) in values() {
            kind.check_value(v)?;
        }
        for (kind, v) in self.dahl_on_x() {
            finite(&super::super::on_x::placed_name(kind), v)?;
            kind.check_value(v)?;
        }
        self.on_x.validate()?;
        check_asymmetry(self.asymmetry, bw.beta(), bw.gamma())
    }

    /// `"name = value, ..."` of the present (non-zero) terms, for error messages.
    pub fn describe(&self) -> String {
        let usual = TermKind::ALL.into_iter().filter_map(|k| {
            self.get(k)
                .filter(|v| *v != 0.0)
                .map(|v| (k.name().to_string(), v))
        });
        let mut on_x = self.on_x;
        let placed = [
            TermKind::Stiffness,
            TermKind::Viscous,
            TermKind::Inertia,
            TermKind::Coulomb,
        ]
        .into_iter()
        .filter_map(|k| {
            let v = *on_x.slot(k)?;
            (v != 0.0).then(|| (super::super::on_x::placed_name(k), v))
        })
        .collect::<Vec<_>>();
        let dahl_x = self
            .dahl_on_x()
            .into_iter()
            .filter(|&(_, v)| v != 0.0)
            .map(|(k, v)| (super::super::on_x::placed_name(k), v));
        let all: Vec<String> = usual
            .chain(placed)
            .chain(dahl_x)
            .map(|(name, v)| format!("{name} = {v:e}"))
            .collect();
        if all.is_empty() {
            "none".into()
        } else {
            all.join(", ")
        }
    }

    /// `true` when a term needs a state or changes `w` (asymmetry, play, sensor lag,
    /// degradation of strength or stiffness, pinching).
    pub fn is_dynamic(&self) -> bool {
        self.asymmetry != 0.0
            || self.play > 0.0
            || self.sensor_lag > 0.0
            || self.degradation > 0.0
            || self.stiffness_degradation > 0.0
            || self.pinching > 0.0
            || self.series_dashpot > 0.0
            || self.dahl_active()
    }

    /// `true` when Dahl friction moves at either place (level and stiffness both > 0).
    pub fn dahl_active(&self) -> bool {
        (self.dahl > 0.0 && self.dahl_sigma > 0.0) || (self.dahl_x > 0.0 && self.dahl_sigma_x > 0.0)
    }
}
