//! The hysteresis behind the augmented model's terms: the plain steady loop, the loop along the input
//! path (asymmetry, play, pinching, a distorted waveform) or behind Spencer's series dashpot, each
//! with its columns in the path loop's `PD_*` order.

use crate::error::{CoreError, Result};
use crate::path_loop::{
    path_loop, path_loop_distorted, path_loop_pinched, Waveform, N_PD, PD_AMPLITUDE, PD_BETA,
    PD_DELTA, PD_GAMMA, PD_MU, PD_PHI,
};
use crate::series_loop::{
    series_loop, SD_AMPLITUDE, SD_BETA, SD_DELTA, SD_GAMMA, SD_MU, SD_PHI, SD_R,
};
use crate::steady::{steady_loop, D_AMPLITUDE, D_BETA, D_GAMMA, D_MU, D_PHI};
use crate::terms::{TermKind, Terms};

/// The hysteresis `w` and its columns `d/d(beta, gamma, mu, A, phi, delta, b)` (the last two 0
/// for the plain loop).
#[allow(clippy::too_many_arguments)]
pub(super) fn hysteresis(
    terms: &Terms,
    shared: &[f64],
    amplitude: f64,
    phi: f64,
    waveform: &[f64],
    p: usize,
    substeps: usize,
) -> Result<(Vec<f64>, Vec<[f64; N_PD]>)> {
    let (beta, gamma, mu) = (shared[0], shared[1], shared[2]);
    if terms.needs_path_loop() {
        let delta = terms.value(shared, TermKind::Asymmetry);
        let b = terms.value(shared, TermKind::Play);
        let wf = terms.column(TermKind::Distortion).map(|c| Waveform {
            lambda: shared[c],
            harmonics: waveform,
        });
        let l = match (terms.column(TermKind::Pinching), &wf) {
            // Pinching: Foliente's factor on h(w, s) (rust/path_loop.rs).
            (Some(c), wf) => path_loop_pinched(
                amplitude,
                beta,
                gamma,
                mu,
                delta,
                b,
                phi,
                shared[c],
                wf.as_ref(),
                p,
                substeps,
            )?,
            (None, Some(wf)) => {
                path_loop_distorted(amplitude, beta, gamma, mu, delta, b, phi, wf, p, substeps)?
            }
            (None, None) => path_loop(amplitude, beta, gamma, mu, delta, b, phi, p, substeps)?,
        };
        Ok((l.w, l.jac))
    } else {
        let l = steady_loop(amplitude, beta, gamma, mu, phi, p, substeps)?;
        const PLAIN: [(usize, usize); 5] = [
            (PD_BETA, D_BETA),
            (PD_GAMMA, D_GAMMA),
            (PD_MU, D_MU),
            (PD_AMPLITUDE, D_AMPLITUDE),
            (PD_PHI, D_PHI),
        ];
        let jac = l.jac.iter().map(|r| pd_row(r, &PLAIN)).collect();
        Ok((l.w, jac))
    }
}

/// `w`, its rows of columns `PD_*`, and `d w / d rho` per sample.
type SeriesHysteresis = (Vec<f64>, Vec<[f64; N_PD]>, Vec<f64>);

/// The hysteresis behind Spencer's series dashpot (`rust/series_loop.rs`) with its columns
/// `d/d(beta, gamma, mu, A, phi, delta)` as [`hysteresis`]'s rows and `d/drho` per sample
/// (`r = rho / omega`). Asymmetry rides along; play, pinching and a distorted waveform do not
/// (a named error).
#[allow(clippy::too_many_arguments)]
pub(super) fn series_hysteresis(
    terms: &Terms,
    shared: &[f64],
    amplitude: f64,
    phi: f64,
    omega: f64,
    rho: f64,
    p: usize,
    substeps: usize,
) -> Result<SeriesHysteresis> {
    for other in [TermKind::Play, TermKind::Pinching, TermKind::Distortion] {
        if terms.column(other).is_some() {
            return Err(CoreError::InvalidParameter(format!(
                "term {:?} with {:?}: the series dashpot's steady loop carries the asymmetry only",
                TermKind::SeriesDashpot.name(),
                other.name()
            )));
        }
    }
    let delta = terms.value(shared, TermKind::Asymmetry);
    let (beta, gamma, mu) = (shared[0], shared[1], shared[2]);
    let l = series_loop(
        amplitude,
        beta,
        gamma,
        mu,
        delta,
        phi,
        rho / omega,
        p,
        substeps,
    )?;
    const SERIES: [(usize, usize); 6] = [
        (PD_BETA, SD_BETA),
        (PD_GAMMA, SD_GAMMA),
        (PD_MU, SD_MU),
        (PD_AMPLITUDE, SD_AMPLITUDE),
        (PD_PHI, SD_PHI),
        (PD_DELTA, SD_DELTA),
    ];
    let jac = l.jac.iter().map(|r| pd_row(r, &SERIES)).collect();
    let d_rho = l.jac.iter().map(|r| r[SD_R] / omega).collect();
    Ok((l.w, jac, d_rho))
}

/// A loop's Jacobian row `r` in the path loop's columns: `(PD_* column, column of r)` pairs, the
/// path loop's other columns 0.
fn pd_row(r: &[f64], columns: &[(usize, usize)]) -> [f64; N_PD] {
    let mut row = [0.0; N_PD];
    for &(to, from) in columns {
        row[to] = r[from];
    }
    row
}
