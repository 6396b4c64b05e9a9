//! The regressors of the terms that are not the hysteresis' own: Dahl friction's steady loops (on u
//! and on x) and the mechanical terms acting across the hysteretic element, on x.

use super::Excitation;
use crate::dahl::{dahl_loop, DahlLoop};
use crate::error::Result;
use crate::terms::{Place, TermKind, Terms};

/// The steady Dahl loops of the active Dahl friction, `(on u, on x)` (rust/dahl.rs): on u driven
/// by `u_j = U cos(theta_j + psi)`, on x by `x_j = U g cos(theta_j - phi)`.
pub(super) fn dahl_loops(
    terms: &Terms,
    shared: &[f64],
    exc: &Excitation,
    gain: f64,
    phase: f64,
) -> Result<[Option<DahlLoop>; 2]> {
    let at = |place: Place, a: f64, psi0: f64| -> Result<Option<DahlLoop>> {
        match (
            terms.column_at(TermKind::Dahl, place),
            terms.column_at(TermKind::DahlSigma, place),
        ) {
            (Some(cf), Some(cs)) => Ok(Some(dahl_loop(
                a,
                psi0,
                shared[cf],
                shared[cs],
                exc.samples,
            )?)),
            _ => Ok(None),
        }
    };
    Ok([
        at(Place::Usual, exc.amplitude, exc.grid_phase)?,
        at(Place::X, exc.amplitude * gain, -phase)?,
    ])
}

/// The Dahl loop of a Dahl parameter's term at `place`, and whether it acts on x; `None` for
/// the other terms.
pub(super) fn dahl_of(
    dahl: &[Option<DahlLoop>; 2],
    kind: TermKind,
    place: Place,
) -> Option<(&DahlLoop, bool)> {
    if !matches!(kind, TermKind::Dahl | TermKind::DahlSigma) {
        return None;
    }
    let on_x = place == Place::X;
    dahl[usize::from(on_x)].as_ref().map(|l| (l, on_x))
}

/// The regressor of a mechanical term acting across the hysteretic element, on its input
/// `x = a cos(z)`, `z = theta_j - phi` (design.md 9.1, place x), with its derivatives in `a` and
/// `phi`: `k x`, `c xdot`, `m xddot`, `f tanh(xdot / (eps |a| omega))` (`eps` the smoothing). The distortion term's
/// harmonics are not seen here (the on-u terms see the measured u: `MeasuredInput`).
pub(super) fn on_x_regressor(
    kind: TermKind,
    a: f64,
    omega: f64,
    z: f64,
    eps: f64,
) -> (f64, f64, f64) {
    let (s, c) = z.sin_cos();
    match kind {
        TermKind::Stiffness => (a * c, c, a * s),
        TermKind::Viscous => (-a * omega * s, -omega * s, a * omega * c),
        TermKind::Inertia => (
            -a * omega * omega * c,
            -omega * omega * c,
            -a * omega * omega * s,
        ),
        TermKind::Coulomb => {
            // xdot / (eps |a| omega) = -sgn(a) sin z / eps: independent of |a|.
            let sg = a.signum();
            let v = (-sg * s / eps).tanh();
            (v, 0.0, (1.0 - v * v) * sg * c / eps)
        }
        // Refused by `Terms::parse` (`TermKind::acts_at`).
        _ => (0.0, 0.0, 0.0),
    }
}
