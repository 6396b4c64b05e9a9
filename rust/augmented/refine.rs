//! The joint Levenberg-Marquardt of the augmented model over every experiment (design.md 9.3): the
//! experiments, the model's constraints and projection, and the checks of a start.

use super::{check_shared, output_on, Excitation, InputColumns, MeasuredInput};
use crate::error::{CoreError, Result};
use crate::refine::{
    check_joint_start, check_start_point, hysteresis_admissible, hysteresis_constraints,
    levenberg_marquardt, project_hysteresis, Constraint, JointModel, ModelEval, Options,
    StopReason,
};
use crate::terms::{Place, TermKind, Terms, PINCHING_MAX};

/// One experiment of the augmented refinement: its averaged period (with its DC), excitation and
/// weight.
#[derive(Debug, Clone, Copy)]
pub struct AugExperiment<'a> {
    /// Averaged output over one period, length P, on `t_j = j T / P` ([y], DC kept).
    pub ybar: &'a [f64],
    /// Input amplitude U ([u], non-zero).
    pub amplitude: f64,
    /// Angular frequency omega (rad/s).
    pub frequency: f64,
    /// Grid phase psi (rad) of the input on the averaged period's grid.
    pub grid_phase: f64,
    /// Weight of each squared residual, `N / sigma^2`.
    pub weight: f64,
    /// The measured input's waveform beyond its fundamental, `[Re c_2, Im c_2, ...]` (design.md
    /// 9.5; empty for a pure sine), used by the `distortion` term.
    pub waveform: &'a [f64],
    /// The measured input's own harmonics and mean as the terms on u see them ([`MeasuredInput`]).
    pub input: MeasuredInput<'a>,
    /// RK4 steps per lattice interval / path segment for this experiment; `None`: the refinement's
    /// [`Options::substeps`]. A coarse grid needs more steps per sample than a fine one for the
    /// same step in phase, so one count for all would make every fine grid pay for the coarsest.
    pub substeps: Option<usize>,
}

impl AugExperiment<'_> {
    fn excitation(&self) -> Excitation {
        Excitation {
            samples: self.ybar.len(),
            amplitude: self.amplitude,
            frequency: self.frequency,
            grid_phase: self.grid_phase,
        }
    }
}

/// Outcome of [`augmented_refine`].
#[derive(Debug, Clone)]
pub struct AugFit {
    /// `[beta, gamma, mu, q_1 .. q_T]` at the minimiser.
    pub shared: Vec<f64>,
    /// Signed gains `g_i`.
    pub gains: Vec<f64>,
    /// Phases `phi_i` (rad, grid frame).
    pub phases: Vec<f64>,
    /// Weighted residual sum of squares.
    pub cost: f64,
    /// Accepted plus rejected LM iterations.
    pub iterations: usize,
    /// Whether a stopping rule other than the iteration cap ended the search.
    pub converged: bool,
    /// The stopping rule that ended the search.
    pub stop: StopReason,
    /// The constraints the minimiser sits on and that hold it there (e.g. `"beta=gamma"`,
    /// `"mu=lower"`, `"sensor_lag=0"`, `"play=upper"`).
    pub active: Vec<String>,
    /// `J^T W J`, order `[beta, gamma, mu, q_1 .. q_T, g_0, phi_0, g_1, phi_1, ...]`.
    pub fisher: nalgebra::DMatrix<f64>,
    /// Model outputs `y_i` at the minimiser.
    pub outputs: Vec<Vec<f64>>,
}

/// Largest play as a fraction of the smallest `|A_i|`: beyond it some experiment's hysteresis
/// barely moves and its loop is ill-determined.
pub const PLAY_MAX_FRACTION: f64 = 0.95;

struct AugModel<'a> {
    exps: &'a [AugExperiment<'a>],
    terms: &'a Terms,
    opts: &'a Options,
    /// Each experiment's measured-input columns ([`InputColumns`]), computed once per refinement.
    inputs: Vec<InputColumns>,
}

impl<'a> AugModel<'a> {
    fn new(exps: &'a [AugExperiment<'a>], terms: &'a Terms, opts: &'a Options) -> Self {
        let inputs = exps
            .iter()
            .map(|e| InputColumns::new(&e.excitation(), &e.input, terms))
            .collect();
        Self {
            exps,
            terms,
            opts,
            inputs,
        }
    }

    /// The columns of Dahl friction's two parameters (>= 0) at every place, with their names.
    fn dahl_columns(&self) -> Vec<(usize, String)> {
        let mut out = Vec::new();
        for place in [Place::Usual, Place::X] {
            for kind in [TermKind::Dahl, TermKind::DahlSigma] {
                if let Some(c) = self.terms.column_at(kind, place) {
                    let name = if place == Place::Usual {
                        kind.name().to_string()
                    } else {
                        format!("{}@{}", kind.name(), place.tag())
                    };
                    out.push((c, name));
                }
            }
        }
        out
    }

    fn play_max(&self, own: &[[f64; 2]]) -> f64 {
        PLAY_MAX_FRACTION
            * self
                .exps
                .iter()
                .zip(own)
                .map(|(e, o)| (e.amplitude * o[0]).abs())
                .fold(f64::INFINITY, f64::min)
    }
}

impl JointModel for AugModel<'_> {
    fn n_shared(&self) -> usize {
        self.terms.n_shared()
    }

    fn n_experiments(&self) -> usize {
        self.exps.len()
    }

    fn data(&self, i: usize) -> (&[f64], f64) {
        (self.exps[i].ybar, self.exps[i].weight)
    }

    fn evaluate(&self, i: usize, shared: &[f64], own: [f64; 2]) -> Result<ModelEval> {
        let out = output_on(
            &self.exps[i].excitation(),
            self.exps[i].waveform,
            &self.inputs[i],
            self.terms,
            shared,
            (own[0], own[1]),
            self.exps[i].substeps.unwrap_or(self.opts.substeps),
        )?;
        Ok(ModelEval {
            y: out.y,
            jac_shared: out.jac_shared,
            jac_own: out.jac_own,
        })
    }

    fn constraints(&self, own: &[[f64; 2]]) -> Vec<Constraint> {
        let mut cons = hysteresis_constraints(self.opts.mu_lo, self.opts.mu_hi);
        // The terms' closed ranges, as `project` clips them: `name=0` and `name=upper`.
        let mut bound = |kind: TermKind, upper: Option<f64>| {
            if let Some(c) = self.terms.column(kind) {
                cons.push(Constraint {
                    name: format!("{}=0", kind.name()),
                    normal: vec![(c, 1.0)],
                    bound: 0.0,
                });
                if let Some(hi) = upper {
                    cons.push(Constraint {
                        name: format!("{}=upper", kind.name()),
                        normal: vec![(c, -1.0)],
                        bound: -hi,
                    });
                }
            }
        };
        bound(TermKind::SensorLag, None);
        bound(TermKind::Play, Some(self.play_max(own)));
        bound(TermKind::Pinching, Some(PINCHING_MAX));
        bound(TermKind::SeriesDashpot, None);
        for (c, name) in self.dahl_columns() {
            cons.push(Constraint {
                name: format!("{name}=0"),
                normal: vec![(c, 1.0)],
                bound: 0.0,
            });
        }
        cons
    }

    fn project(&self, shared: &mut [f64], own: &[[f64; 2]]) {
        project_hysteresis(shared, self.opts.mu_lo, self.opts.mu_hi);
        if let Some(c) = self.terms.column(TermKind::SensorLag) {
            shared[c] = shared[c].max(0.0);
        }
        if let Some(c) = self.terms.column(TermKind::Play) {
            shared[c] = shared[c].min(self.play_max(own)).max(0.0);
        }
        if let Some(c) = self.terms.column(TermKind::Pinching) {
            shared[c] = shared[c].clamp(0.0, PINCHING_MAX);
        }
        if let Some(c) = self.terms.column(TermKind::SeriesDashpot) {
            shared[c] = shared[c].max(0.0);
        }
        for (c, _) in self.dahl_columns() {
            shared[c] = shared[c].max(0.0);
        }
    }

    fn admissible(&self, shared: &[f64], own: &[[f64; 2]]) -> bool {
        let delta_ok = self
            .terms
            .column(TermKind::Asymmetry)
            .is_none_or(|c| shared[c].abs() < shared[0] + shared[1]);
        let tau_ok = self
            .terms
            .column(TermKind::SensorLag)
            .is_none_or(|c| shared[c] >= 0.0);
        let play_ok = self
            .terms
            .column(TermKind::Play)
            .is_none_or(|c| shared[c] >= 0.0 && shared[c] <= self.play_max(own));
        let pinch_ok = self
            .terms
            .column(TermKind::Pinching)
            .is_none_or(|c| (0.0..=PINCHING_MAX).contains(&shared[c]));
        let series_ok = self
            .terms
            .column(TermKind::SeriesDashpot)
            .is_none_or(|c| shared[c] >= 0.0);
        let dahl_ok = self.dahl_columns().iter().all(|&(c, _)| shared[c] >= 0.0);
        hysteresis_admissible(shared, self.opts.mu_lo, self.opts.mu_hi)
            && dahl_ok
            && series_ok
            && pinch_ok
            && delta_ok
            && tau_ok
            && play_ok
    }
}

fn validate_refine(
    exps: &[AugExperiment],
    terms: &Terms,
    shared: &[f64],
    gains: &[f64],
    phases: &[f64],
    opts: &Options,
) -> Result<()> {
    let model = AugModel {
        exps,
        terms,
        opts,
        inputs: Vec::new(),
    };
    let excitation = |i: usize| exps[i].excitation().validate();
    check_joint_start(&model, excitation, (gains, phases), opts)?;
    if !opts.mu_lo.is_finite()
        || opts.mu_lo < 1.0
        || opts.mu_hi.is_nan()
        || opts.mu_hi <= opts.mu_lo
    {
        return Err(CoreError::InvalidParameter(format!(
            "the mu bracket ({}, {}] must have a finite lower end >= 1 below its upper end",
            opts.mu_lo, opts.mu_hi
        )));
    }
    check_shared(terms, shared)?;
    // mu_lo >= 1 here (the bracket is checked above): the message names the bracket as given.
    check_start_point(shared, opts)?;
    let b = terms.value(shared, TermKind::Play);
    let own: Vec<[f64; 2]> = gains.iter().zip(phases).map(|(&g, &p)| [g, p]).collect();
    if b > model.play_max(&own) {
        return Err(CoreError::InvalidParameter(format!(
            "the starting play b = {b} must be below {PLAY_MAX_FRACTION} min |U_i g_i| = {}",
            model.play_max(&own)
        )));
    }
    Ok(())
}

/// Joint Levenberg-Marquardt of the augmented model over every experiment (design.md 9.3).
///
/// `shared0 = [beta, gamma, mu, q_1 .. q_T]` in the order of `terms`; `gains0`, `phases0` one per
/// experiment. Same damping schedule, stopping rules and Schur solve as [`crate::refine::refine`]
/// ([`levenberg_marquardt`]); trial points are projected onto `beta = gamma` and the mu bracket,
/// `tau` and `b` are clipped at 0 and `b` below [`PLAY_MAX_FRACTION`] `min |A_i|`, and a trial
/// point with `|delta| >= beta + gamma` is rejected.
///
/// Errors: inconsistent lengths, non-finite or inadmissible start, bad mu bracket, non-positive
/// weight, and every error of [`augmented_output`] at the start.
pub fn augmented_refine(
    exps: &[AugExperiment],
    terms: &Terms,
    shared0: &[f64],
    gains0: &[f64],
    phases0: &[f64],
    opts: &Options,
) -> Result<AugFit> {
    validate_refine(exps, terms, shared0, gains0, phases0, opts)?;
    let model = AugModel::new(exps, terms, opts);
    let own: Vec<[f64; 2]> = gains0.iter().zip(phases0).map(|(&g, &p)| [g, p]).collect();
    let fit = levenberg_marquardt(&model, shared0, &own, opts)?;
    Ok(AugFit {
        gains: fit.own.iter().map(|o| o[0]).collect(),
        phases: fit.own.iter().map(|o| o[1]).collect(),
        shared: fit.shared,
        cost: fit.cost,
        iterations: fit.iterations,
        converged: fit.converged,
        stop: fit.stop,
        active: fit.active,
        fisher: fit.fisher,
        outputs: fit.outputs,
    })
}
