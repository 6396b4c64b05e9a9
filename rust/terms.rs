//! The vocabulary of the physical terms (`docs/design.md` 9.1, 9.4): every term the core knows,
//! its code name, where it acts, and the admissible range of its parameter that does not depend
//! on the rest of the model.
//!
//! This is the one place in Rust where a term's code name is written: [`TermKind::name`]. The
//! augmented (steady-loop) model of `rust/augmented.rs` fits the terms of a [`Terms`] list; the
//! time-domain simulation of `rust/simulate/with_terms.rs` takes a value per term. Adding a term
//! is a variant here, its arm in [`TermKind::name`] (and [`TermKind::check_value`] if its range is
//! one-sided), and its behaviour in the model(s) it acts in.
//!
//! Depends on nothing but [`crate::error`], so that both models can use it without a cycle.

use crate::error::{finite, CoreError, Result};

/// Default width `eps` of the smoothed Coulomb sign `tanh(udot / (eps Vmax))`: 1 % of the peak
/// input velocity `Vmax` (§9.1). The augmented model uses it; the simulation takes it as the
/// Coulomb term's second parameter ([`COULOMB_SMOOTHING_KEY`]).
pub const COULOMB_SMOOTHING: f64 = 0.01;

/// Largest admissible `eps` of the smoothed Coulomb sign: beyond half the peak velocity the
/// `tanh` no longer resembles a sign.
pub const COULOMB_SMOOTHING_MAX: f64 = 0.5;

/// Number of shared hysteresis parameters ahead of the terms: `beta, gamma, mu`.
pub const N_HYSTERESIS: usize = 3;

/// Where a term acts (design.md 9.1). Every term has its usual place; the mechanical terms
/// (stiffness, viscous, inertia, Coulomb) can also act across the hysteretic element, on its own
/// input x. A caller names a term at a place other than its usual one as `"<name>@<tag>"`
/// ([`Place::tag`]); a new place is a variant here, its tag, and its arm in the models.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Place {
    /// The term's usual place: the mechanical terms on the measured input u (beside the cascade).
    Usual,
    /// Across the hysteretic element, on its input `x = G u` (in parallel with it).
    X,
}

impl Place {
    /// Every place other than [`Place::Usual`], which has no tag.
    pub const OTHERS: [Place; 1] = [Place::X];

    /// The tag after `@` in a placed term's name (`""` for the usual place).
    pub fn tag(self) -> &'static str {
        match self {
            Place::Usual => "",
            Place::X => "x",
        }
    }
}

/// One physical term beyond the Wiener-Bouc-Wen model, each with exactly one parameter.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum TermKind {
    /// Output offset `y0` ([y]).
    Offset,
    /// Parallel stiffness `k` ([y]/[u]).
    Stiffness,
    /// Viscous damping `c` ([y] s/[u]).
    Viscous,
    /// Inertia `m` ([y] s^2/[u]).
    Inertia,
    /// Dry (Coulomb) friction `f` ([y]), sign smoothed by `tanh` over [`COULOMB_SMOOTHING`].
    Coulomb,
    /// First-order output (sensor) lag `tau` (s), `tau >= 0`.
    SensorLag,
    /// Asymmetry `delta` (1/[w]^mu), `|delta| < beta + gamma`.
    Asymmetry,
    /// Play (backlash) half-width `b` ([x]) before the hysteresis, `b >= 0` (and `b < |A|`).
    Play,
    /// Measured input waveform: `lambda` (dimensionless) scales the input's own harmonics in the
    /// latent x (design.md 9.5); each experiment supplies its waveform. Steady-loop model only.
    Distortion,
    /// Strength degradation `delta_nu` (1/([w] [x])), `>= 0`: Baber-Noori `nu = 1 + delta_nu e`,
    /// `e = int w dxp` (§9.4). Simulation only: the steady loop has no fixed point with it.
    Degradation,
    /// Stiffness degradation `delta_eta` (1/([w] [x])), `>= 0`: Baber-Noori `eta = 1 + delta_eta e`
    /// divides the whole Bouc-Wen rate (§9.4). Simulation only, as [`TermKind::Degradation`].
    StiffnessDegradation,
    /// Pinching `zeta1` (dimensionless), `0 <= zeta1 < 1`: the rate times Foliente's
    /// `h = 1 - zeta1 exp(-((w sgn(xpdot) - q w_u) / (z2 w_u))^2)`, shape fixed
    /// ([`PINCHING_CENTRE`], [`PINCHING_WIDTH`]), `w_u = (alpha/(beta + gamma))^(1/mu)` (§9.4).
    /// Rate independent: the steady loop of 9.2 carries it (`rust/path_loop.rs`).
    Pinching,
    /// Series dashpot `rho` (1/s in the identified model; `[x]/([w] s)` in general), `>= 0`:
    /// Spencer's MR-damper dashpot in series with the hysteretic element. The element is driven
    /// by its own travel `d = x - q`, `ddot = xdot - rho w` (the dashpot creeps at `qdot = rho w`
    /// under the element's force), so `wdot = ddot h(w, sgn ddot)` (design.md 9.1, diagnosis.md).
    /// Rate dependent: its steady loop is solved in time (`rust/series_loop.rs`).
    SeriesDashpot,
    /// Dahl friction's level `Fc` ([y]), `>= 0`: `F' = sigma v' (1 - sgn(v') F / Fc)` along the
    /// travel v of its place (u, or x across the hysteretic element), added to the output. It
    /// comes with its pre-sliding stiffness [`TermKind::DahlSigma`] at the same place (the two
    /// parameters of one element). Its steady loop is closed form (`rust/dahl.rs`).
    Dahl,
    /// Dahl friction's pre-sliding stiffness `sigma` ([y]/[u] on u, dimensionless on x), `>= 0`:
    /// the second parameter of [`TermKind::Dahl`], given with it at the same place.
    DahlSigma,
}

/// Centre `q` of the pinching band, a fraction of the saturation level `w_u`, on the branch of the
/// motion (`w sgn(xpdot) = q w_u`): the slip sits just past the zero crossing of w after a reversal.
pub const PINCHING_CENTRE: f64 = 0.1;

/// Width `zeta2` of the pinching band, a fraction of the saturation level `w_u`.
pub const PINCHING_WIDTH: f64 = 0.2;

/// Largest `zeta1` the steady-loop fit admits (at 1 the loop would stop at the band's centre).
pub const PINCHING_MAX: f64 = 0.95;

impl TermKind {
    /// Every term, in the order of the table of design.md 9.1 (then the simulation-only one).
    pub const ALL: [TermKind; 15] = [
        TermKind::Offset,
        TermKind::Stiffness,
        TermKind::Viscous,
        TermKind::Inertia,
        TermKind::Coulomb,
        TermKind::SensorLag,
        TermKind::Asymmetry,
        TermKind::Play,
        TermKind::Distortion,
        TermKind::Degradation,
        TermKind::StiffnessDegradation,
        TermKind::Pinching,
        TermKind::SeriesDashpot,
        TermKind::Dahl,
        TermKind::DahlSigma,
    ];

    /// The code name (design.md 9.1), e.g. `"sensor_lag"`: the only place a term's name is
    /// written in Rust.
    pub fn name(self) -> &'static str {
        match self {
            TermKind::Offset => "offset",
            TermKind::Stiffness => "stiffness",
            TermKind::Viscous => "viscous",
            TermKind::Inertia => "inertia",
            TermKind::Coulomb => "coulomb",
            TermKind::SensorLag => "sensor_lag",
            TermKind::Asymmetry => "asymmetry",
            TermKind::Play => "play",
            TermKind::Distortion => "distortion",
            TermKind::Degradation => "degradation",
            TermKind::StiffnessDegradation => "stiffness_degradation",
            TermKind::Pinching => "pinching",
            TermKind::SeriesDashpot => "series_dashpot",
            TermKind::Dahl => "dahl",
            TermKind::DahlSigma => "dahl_sigma",
        }
    }

    /// The term of a code name; an unknown name is [`CoreError::InvalidParameter`] listing the
    /// known ones.
    pub fn from_name(name: &str) -> Result<Self> {
        Self::ALL
            .iter()
            .copied()
            .find(|k| k.name() == name)
            .ok_or_else(|| {
                CoreError::InvalidParameter(format!(
                    "unknown term {name:?}; the terms are {}",
                    names(Self::ALL.iter().copied())
                ))
            })
    }

    /// Whether the augmented (steady-loop) model of design.md 9.1 has this term.
    pub fn in_steady_loop(self) -> bool {
        !matches!(self, TermKind::Degradation | TermKind::StiffnessDegradation)
    }

    /// Whether the term can act at `place` (every term at its usual place; the mechanical terms
    /// also across the hysteretic element, on x).
    pub fn acts_at(self, place: Place) -> bool {
        match place {
            Place::Usual => true,
            Place::X => matches!(
                self,
                TermKind::Stiffness
                    | TermKind::Viscous
                    | TermKind::Inertia
                    | TermKind::Coulomb
                    | TermKind::Dahl
                    | TermKind::DahlSigma
            ),
        }
    }

    /// Whether the time-domain simulation of design.md 9.4 has this term.
    pub fn in_simulation(self) -> bool {
        self != TermKind::Distortion
    }

    /// Whether the term changes the hysteresis' input path (the steady-loop model then solves
    /// the loop along the path of design.md 9.2).
    pub fn acts_on_path(self) -> bool {
        matches!(
            self,
            TermKind::Asymmetry | TermKind::Play | TermKind::Distortion | TermKind::Pinching
        )
    }

    /// Checks the one-sided range of the term's value (`tau >= 0`, `b >= 0`, `delta_nu >= 0`);
    /// `value` must be finite already. The asymmetry's range depends on the hysteresis: see
    /// [`check_asymmetry`].
    ///
    /// Errors: [`CoreError::InvalidParameter`] naming the term.
    pub fn check_value(self, value: f64) -> Result<()> {
        let (symbol, why) = match self {
            TermKind::SensorLag => ("tau", "s must be >= 0"),
            TermKind::Play => ("b", "must be >= 0 (the half-width of the backlash)"),
            TermKind::Degradation => (
                "delta_nu",
                "must be >= 0 (the strength falls with dissipated energy)",
            ),
            TermKind::StiffnessDegradation => (
                "delta_eta",
                "must be >= 0 (the stiffness falls with dissipated energy)",
            ),
            TermKind::SeriesDashpot => (
                "rho",
                "must be >= 0 (the inverse of the series dashpot's coefficient; 0: no dashpot)",
            ),
            TermKind::Dahl => ("Fc", "must be >= 0 (the friction level; 0: no friction)"),
            TermKind::DahlSigma => (
                "sigma",
                "must be >= 0 (the pre-sliding stiffness of the Dahl friction)",
            ),
            TermKind::Pinching => {
                if !(0.0..1.0).contains(&value) {
                    return Err(CoreError::InvalidParameter(format!(
                        "{} zeta1 = {value} must be in [0, 1) (the share of the rate taken out at \
                         the pinching band's centre)",
                        self.name()
                    )));
                }
                return Ok(());
            }
            _ => return Ok(()),
        };
        if value < 0.0 {
            return Err(CoreError::InvalidParameter(format!(
                "{} {symbol} = {value} {why}",
                self.name()
            )));
        }
        Ok(())
    }
}

/// `"a, b, c"` of the terms' code names.
fn names(kinds: impl Iterator<Item = TermKind>) -> String {
    kinds.map(TermKind::name).collect::<Vec<_>>().join(", ")
}

/// Checks the asymmetry against the hysteresis: `|delta| < beta + gamma`, else one side of the
/// loop is unbounded.
///
/// Errors: [`CoreError::InvalidParameter`].
pub fn check_asymmetry(delta: f64, beta: f64, gamma: f64) -> Result<()> {
    let bound = beta + gamma;
    if delta.abs() >= bound {
        return Err(CoreError::InvalidParameter(format!(
            "{} |delta| = {} must be < beta + gamma = {bound} for a bounded output on both sides",
            TermKind::Asymmetry.name(),
            delta.abs()
        )));
    }
    Ok(())
}

/// Checks the Coulomb smoothing width `eps` of the simulation: finite, in
/// `(0, `[`COULOMB_SMOOTHING_MAX`]`]`.
///
/// Errors: [`CoreError::NonFinite`], [`CoreError::InvalidParameter`].
pub fn check_coulomb_smoothing(eps: f64) -> Result<()> {
    finite(COULOMB_SMOOTHING_KEY, eps)?;
    if !(eps > 0.0 && eps <= COULOMB_SMOOTHING_MAX) {
        return Err(CoreError::InvalidParameter(format!(
            "{COULOMB_SMOOTHING_KEY} eps = {eps} must be in (0, {COULOMB_SMOOTHING_MAX}]"
        )));
    }
    Ok(())
}

/// The key of the Coulomb term's smoothing width in a simulation's `{name: value}` map: a
/// setting of the `coulomb` term, not a term of its own.
pub const COULOMB_SMOOTHING_KEY: &str = "coulomb_smoothing";

/// The active terms of the augmented model, in the order their parameters follow
/// `beta, gamma, mu` in the shared vector.
#[derive(Debug, Clone, PartialEq)]
pub struct Terms {
    kinds: Vec<TermKind>,
    /// The place of each term, parallel to `kinds`.
    places: Vec<Place>,
    /// The dry friction's smoothing width `eps` (a fraction of the peak velocity at its place),
    /// a setting of the Coulomb terms, not a parameter the refinement moves:
    /// [`COULOMB_SMOOTHING`] unless [`Terms::with_smoothing`] sets it.
    smoothing: f64,
}

impl Default for Terms {
    fn default() -> Self {
        Self {
            kinds: Vec::new(),
            places: Vec::new(),
            smoothing: COULOMB_SMOOTHING,
        }
    }
}

/// Splits a caller's term name `"<code name>[@<place tag>]"` into its kind and place; an unknown
/// place, or a place the term cannot act at, is [`CoreError::InvalidParameter`].
pub fn parse_placed(name: &str) -> Result<(TermKind, Place)> {
    let Some((base, tag)) = name.split_once('@') else {
        return Ok((TermKind::from_name(name)?, Place::Usual));
    };
    let kind = TermKind::from_name(base)?;
    let place = Place::OTHERS
        .iter()
        .copied()
        .find(|p| p.tag() == tag)
        .ok_or_else(|| {
            CoreError::InvalidParameter(format!(
                "unknown place {tag:?} in term {name:?}; the places are {}",
                Place::OTHERS.map(Place::tag).join(", ")
            ))
        })?;
    if !kind.acts_at(place) {
        return Err(CoreError::InvalidParameter(format!(
            "term {:?} cannot act at place {tag:?}: only the mechanical terms (stiffness, \
             viscous, inertia, Coulomb, Dahl) act across the hysteretic element",
            kind.name()
        )));
    }
    Ok((kind, place))
}

impl Terms {
    /// Parses code names; unknown or repeated names, and terms the steady-loop model does not
    /// have, are [`CoreError::InvalidParameter`].
    pub fn parse<S: AsRef<str>>(names_given: &[S]) -> Result<Self> {
        let mut kinds = Vec::with_capacity(names_given.len());
        let mut places = Vec::with_capacity(names_given.len());
        for n in names_given {
            let (k, place) = parse_placed(n.as_ref())?;
            if !k.in_steady_loop() {
                return Err(CoreError::InvalidParameter(format!(
                    "term {:?} has no steady-loop form (simulation only); the terms of the \
                     augmented model are {}",
                    k.name(),
                    names(TermKind::ALL.iter().copied().filter(|k| k.in_steady_loop()))
                )));
            }
            if kinds
                .iter()
                .zip(&places)
                .any(|(&a, &b)| a == k && b == place)
            {
                return Err(CoreError::InvalidParameter(format!(
                    "term {:?} is given twice; each term has one parameter and may appear once",
                    n.as_ref()
                )));
            }
            kinds.push(k);
            places.push(place);
        }
        let t = Self {
            kinds,
            places,
            smoothing: COULOMB_SMOOTHING,
        };
        t.check_pairs()?;
        Ok(t)
    }

    /// The same terms with the Coulomb smoothing width `eps` ([`check_coulomb_smoothing`]).
    pub fn with_smoothing(mut self, eps: f64) -> Result<Self> {
        check_coulomb_smoothing(eps)?;
        self.smoothing = eps;
        Ok(self)
    }

    /// The Coulomb terms' smoothing width `eps`: `f tanh(v / (eps Vmax))`.
    pub fn smoothing(&self) -> f64 {
        self.smoothing
    }

    /// Checks that Dahl friction's two parameters come together: [`TermKind::Dahl`] and
    /// [`TermKind::DahlSigma`] at the same place, or neither.
    fn check_pairs(&self) -> Result<()> {
        for (&k, &place) in self.kinds.iter().zip(&self.places) {
            let other = match k {
                TermKind::Dahl => TermKind::DahlSigma,
                TermKind::DahlSigma => TermKind::Dahl,
                _ => continue,
            };
            if self.column_at(other, place).is_none() {
                let tag = if place == Place::Usual {
                    String::new()
                } else {
                    format!("@{}", place.tag())
                };
                return Err(CoreError::InvalidParameter(format!(
                    "term \"{}{tag}\" needs \"{}{tag}\": Dahl friction's level and pre-sliding \
                     stiffness are given together",
                    k.name(),
                    other.name()
                )));
            }
        }
        Ok(())
    }

    /// The place of the `t`-th active term.
    pub fn place(&self, t: usize) -> Place {
        self.places[t]
    }

    /// The active terms in order.
    pub fn kinds(&self) -> &[TermKind] {
        &self.kinds
    }

    /// Number of active terms T.
    pub fn len(&self) -> usize {
        self.kinds.len()
    }

    /// Whether no term is active (the plain model).
    pub fn is_empty(&self) -> bool {
        self.kinds.is_empty()
    }

    /// Column of `kind`'s parameter at its usual place in the shared vector
    /// `[beta, gamma, mu, q_1 ..]`, if active.
    pub fn column(&self, kind: TermKind) -> Option<usize> {
        self.column_at(kind, Place::Usual)
    }

    /// Column of `kind`'s parameter at `place`, if active there.
    pub fn column_at(&self, kind: TermKind, place: Place) -> Option<usize> {
        self.kinds
            .iter()
            .zip(&self.places)
            .position(|(&k, &p)| k == kind && p == place)
            .map(|i| N_HYSTERESIS + i)
    }

    /// Size of the shared vector, `3 + T`.
    pub fn n_shared(&self) -> usize {
        N_HYSTERESIS + self.kinds.len()
    }

    /// Whether the hysteresis needs the path loop of 9.2 (a term acting on the path is active).
    pub fn needs_path_loop(&self) -> bool {
        self.kinds.iter().any(|k| k.acts_on_path())
    }

    /// `kind`'s value in `shared`, 0 when inactive (every term vanishes at 0).
    pub fn value(&self, shared: &[f64], kind: TermKind) -> f64 {
        self.column(kind).map_or(0.0, |c| shared[c])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip_and_bad_names_are_named_errors() {
        for k in TermKind::ALL {
            assert_eq!(TermKind::from_name(k.name()).unwrap(), k);
        }
        let (offset, viscous, play) = (
            TermKind::Offset.name(),
            TermKind::Viscous.name(),
            TermKind::Play.name(),
        );
        let e = Terms::parse(&[offset, "frobnicate"]).unwrap_err();
        assert!(e.to_string().contains("unknown term \"frobnicate\""), "{e}");
        let e = Terms::parse(&[viscous, offset, viscous]).unwrap_err();
        assert!(e.to_string().contains("given twice"), "{e}");
        let e = Terms::parse(&[TermKind::Degradation.name()]).unwrap_err();
        assert!(e.to_string().contains("no steady-loop form"), "{e}");
        let t = Terms::parse(&[play, offset]).unwrap();
        assert_eq!(t.column(TermKind::Offset), Some(4));
        assert!(t.needs_path_loop());
    }

    #[test]
    fn placed_names_parse_and_bad_places_are_named_errors() {
        let (viscous, offset) = (TermKind::Viscous.name(), TermKind::Offset.name());
        let on_x = format!("{viscous}@{}", Place::X.tag());
        let t = Terms::parse(&[viscous, on_x.as_str()]).unwrap();
        assert_eq!(t.column(TermKind::Viscous), Some(3));
        assert_eq!(t.column_at(TermKind::Viscous, Place::X), Some(4));
        assert_eq!(t.place(1), Place::X);
        let e = Terms::parse(&[on_x.as_str(), on_x.as_str()]).unwrap_err();
        assert!(e.to_string().contains("given twice"), "{e}");
        let e = Terms::parse(&[format!("{offset}@x")]).unwrap_err();
        assert!(e.to_string().contains("cannot act at place"), "{e}");
        let e = Terms::parse(&[format!("{viscous}@z")]).unwrap_err();
        assert!(e.to_string().contains("unknown place"), "{e}");
    }

    #[test]
    fn dahl_friction_takes_its_two_parameters_together() {
        let (dahl, sigma) = (TermKind::Dahl.name(), TermKind::DahlSigma.name());
        let on_x = |n: &str| format!("{n}@{}", Place::X.tag());
        let t = Terms::parse(&[on_x(dahl), on_x(sigma), dahl.into(), sigma.into()]).unwrap();
        assert_eq!(t.column_at(TermKind::DahlSigma, Place::X), Some(4));
        assert_eq!(t.column(TermKind::Dahl), Some(5));
        let e = Terms::parse(&[dahl]).unwrap_err();
        assert!(e.to_string().contains("given together"), "{e}");
        let e = Terms::parse(&[on_x(sigma), sigma.into()]).unwrap_err();
        assert!(e.to_string().contains("given together"), "{e}");
        let e = Terms::parse(&[on_x(dahl), sigma.into()]).unwrap_err();
        assert!(e.to_string().contains("given together"), "{e}");
        assert!(TermKind::Dahl.in_simulation());
    }

    #[test]
    fn one_sided_ranges_name_the_term() {
        for kind in [
            TermKind::SensorLag,
            TermKind::Play,
            TermKind::Degradation,
            TermKind::StiffnessDegradation,
            TermKind::Pinching,
            TermKind::SeriesDashpot,
            TermKind::Dahl,
            TermKind::DahlSigma,
        ] {
            let e = kind.check_value(-0.1).unwrap_err();
            assert!(e.to_string().contains(kind.name()), "{e}");
            assert!(kind.check_value(0.0).is_ok());
        }
        assert!(TermKind::Viscous.check_value(-1.0).is_ok());
        assert!(TermKind::Pinching.check_value(1.0).is_err());
        assert!(TermKind::Pinching.check_value(0.99).is_ok());
        let e = Terms::parse(&[TermKind::StiffnessDegradation.name()]).unwrap_err();
        assert!(e.to_string().contains("no steady-loop form"), "{e}");
        assert!(Terms::parse(&[TermKind::Pinching.name()])
            .unwrap()
            .needs_path_loop());
        assert!(check_asymmetry(0.5, 0.3, 0.3).is_ok());
        assert!(check_asymmetry(-0.6, 0.3, 0.3).is_err());
        assert!(check_coulomb_smoothing(0.0).is_err());
        assert!(check_coulomb_smoothing(f64::NAN).is_err());
        assert!(check_coulomb_smoothing(COULOMB_SMOOTHING_MAX).is_ok());
    }
}
