//! Tests of the augmented model's output, Jacobian and refinement.

use super::lag::apply_lag;
use super::*;
use crate::refine::Options;
use crate::terms::COULOMB_SMOOTHING;
use TermKind::*;

/// The terms of `kinds`, through their code names as a caller gives them.
fn terms_of(kinds: &[TermKind]) -> Terms {
    let names: Vec<&str> = kinds.iter().map(|k| k.name()).collect();
    Terms::parse(&names).unwrap()
}

const EXC: Excitation = Excitation {
    samples: 64,
    amplitude: 1.7,
    frequency: 3.0,
    grid_phase: 0.4,
};

#[test]
fn lag_filter_is_identity_at_zero_and_a_lag_of_the_fundamental() {
    // A pure fundamental through tau: amplitude 1/sqrt(1 + (omega tau)^2), lag atan(omega tau).
    let (p, omega, tau) = (32usize, 2.0, 0.3);
    let x: Vec<f64> = (0..p)
        .map(|j| (2.0 * std::f64::consts::PI * j as f64 / p as f64).cos())
        .collect();
    let mut y0 = x.clone();
    apply_lag(&mut [&mut y0[..]], omega, 0.0, false);
    let mut y = x.clone();
    apply_lag(&mut [&mut y[..]], omega, tau, false);
    let g = 1.0 / (1.0 + (omega * tau).powi(2)).sqrt();
    let lag = (omega * tau).atan();
    for j in 0..p {
        assert!((y0[j] - x[j]).abs() < 1e-14);
        let th = 2.0 * std::f64::consts::PI * j as f64 / p as f64;
        assert!((y[j] - g * (th - lag).cos()).abs() < 1e-14);
    }
}

/// The code name of `kind` acting on x, as a caller gives it.
fn on_x_name(kind: TermKind) -> String {
    format!("{}@{}", kind.name(), Place::X.tag())
}

/// Central differences of every shared and own column, with step `h` and relative tolerance.
fn check_jacobian(terms: &[TermKind], shared: &[f64], exc: &Excitation, substeps: usize) {
    check_jacobian_at(&terms_of(terms), shared, exc, substeps, 0.9);
}

/// [`check_jacobian`] of parsed terms (placed ones too) at gain `g` and phase 1.1.
fn check_jacobian_at(terms: &Terms, shared: &[f64], exc: &Excitation, substeps: usize, g: f64) {
    let phi = 1.1;
    let out = augmented_output(exc, terms, shared, g, phi, substeps).unwrap();
    let ns = shared.len();
    let h = 1e-6;
    let f =
        |s: &[f64], g: f64, phi: f64| augmented_output(exc, terms, s, g, phi, substeps).unwrap().y;
    for c in 0..ns + 2 {
        let (mut sp, mut sm) = (shared.to_vec(), shared.to_vec());
        let (mut gp, mut gm, mut pp, mut pm) = (g, g, phi, phi);
        match c {
            c if c < ns => {
                sp[c] += h;
                sm[c] -= h;
            }
            c if c == ns => {
                gp += h;
                gm -= h;
            }
            _ => {
                pp += h;
                pm -= h;
            }
        }
        let (yp, ym) = (f(&sp, gp, pp), f(&sm, gm, pm));
        let col: Vec<f64> = (0..exc.samples)
            .map(|j| {
                if c < ns {
                    out.jac_shared[j * ns + c]
                } else {
                    out.jac_own[j][c - ns]
                }
            })
            .collect();
        let scale = col.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        let err = (0..exc.samples)
            .map(|j| ((yp[j] - ym[j]) / (2.0 * h) - col[j]).abs())
            .fold(0.0, f64::max);
        // Central differences err by O(h^2) truncation plus O(eps / h) rounding, about 1e-9
        // relative. The phase column of the plain loop is its continuous rate (7.2), the
        // derivative of the discrete map only up to the RK4 error near w = 0 where |w|^mu is
        // not smooth: 1e-5 relative at 4 substeps, 1e-7 at 256 (measured), hence 256 here.
        assert!(
            err <= 1e-6 * scale.max(1e-3),
            "column {c}: {err} vs {scale}"
        );
    }
}

#[test]
fn jacobian_matches_central_differences() {
    check_jacobian(
        &[Offset, Stiffness, Viscous, Inertia, Coulomb, SensorLag],
        &[0.8, 0.2, 1.6, 0.3, 0.5, 0.05, 0.002, 0.2, 0.01],
        &EXC,
        256,
    );
    check_jacobian(
        &[SensorLag, Asymmetry, Play, Viscous],
        &[0.8, 0.2, 1.6, 0.02, 0.3, 0.2, 0.05],
        &Excitation { samples: 65, ..EXC },
        256,
    );
    check_jacobian(
        &[Pinching, Play, SensorLag],
        &[0.8, 0.2, 1.6, 0.4, 0.05, 0.02],
        &Excitation { samples: 64, ..EXC },
        256,
    );
}

#[test]
fn series_dashpot_jacobian_matches_central_differences() {
    // Spencer's series dashpot (rust/series_loop.rs) with the asymmetry it carries and the
    // output terms around it; the series loop's columns are those of its discrete map.
    check_jacobian(
        &[SeriesDashpot, Asymmetry, SensorLag, Offset],
        &[0.8, 0.2, 1.6, 0.7, -0.1, 0.05, 0.3],
        &Excitation { samples: 48, ..EXC },
        8,
    );
    let both = terms_of(&[SeriesDashpot, Play]);
    let e = augmented_output(&EXC, &both, &[0.8, 0.2, 1.6, 0.5, 0.1], 0.9, 1.1, 4).unwrap_err();
    assert!(e.to_string().contains("asymmetry only"), "{e}");
}

#[test]
fn dahl_jacobian_matches_central_differences() {
    // Dahl friction on u and on x (rust/dahl.rs) beside the lag and a spring on x.
    let names = [
        on_x_name(Dahl),
        Dahl.name().to_string(),
        on_x_name(DahlSigma),
        SensorLag.name().to_string(),
        DahlSigma.name().to_string(),
        on_x_name(Stiffness),
    ];
    let terms = Terms::parse(&names).unwrap();
    let shared = [0.8, 0.2, 1.6, 0.1, 0.05, 0.3, 0.02, 0.4, 0.2];
    check_jacobian_at(&terms, &shared, &EXC, 256, -0.9);
}

#[test]
fn on_x_terms_jacobian_matches_central_differences() {
    let names = [
        on_x_name(Stiffness),
        on_x_name(Viscous),
        on_x_name(Inertia),
        on_x_name(Coulomb),
        Viscous.name().to_string(),
        SensorLag.name().to_string(),
    ];
    let terms = Terms::parse(&names).unwrap();
    let shared = [0.8, 0.2, 1.6, 0.3, 0.05, 0.002, 0.1, 0.02, 0.01];
    check_jacobian_at(&terms, &shared, &EXC, 256, 0.9);
}

#[test]
fn coulomb_smoothing_sets_the_width_at_both_places() {
    // Another width than the default: the Jacobian still matches (the on-x friction's phase column
    // carries 1 / eps), and the friction's column is tanh(udot / (eps U omega)) at that eps.
    let names = [
        on_x_name(Coulomb),
        Coulomb.name().to_string(),
        on_x_name(Viscous),
    ];
    let terms = Terms::parse(&names).unwrap().with_smoothing(0.04).unwrap();
    let shared = [0.8, 0.2, 1.6, 0.1, 0.05, 0.02];
    check_jacobian_at(&terms, &shared, &EXC, 256, 0.9);
    let sharp = Terms::parse(&[Coulomb.name()]).unwrap();
    let wide = sharp.clone().with_smoothing(0.3).unwrap();
    let sh = [0.8, 0.2, 1.6, 0.1];
    let a = augmented_output(&EXC, &sharp, &sh, 0.9, 0.3, 16).unwrap();
    let b = augmented_output(&EXC, &wide, &sh, 0.9, 0.3, 16).unwrap();
    let step = 2.0 * std::f64::consts::PI / EXC.samples as f64;
    for j in 0..EXC.samples {
        let th = step * j as f64 + EXC.grid_phase;
        let v = -th.sin(); // udot / (U omega)
        let want = (v / 0.3).tanh() - (v / COULOMB_SMOOTHING).tanh();
        assert!((b.y[j] - a.y[j] - 0.1 * want).abs() < 1e-12, "sample {j}");
    }
    assert!(Terms::parse(&[Coulomb.name()])
        .unwrap()
        .with_smoothing(0.0)
        .is_err());
    assert!(Terms::parse(&[Coulomb.name()])
        .unwrap()
        .with_smoothing(0.6)
        .is_err());
}

/// `y` of experiment `i` with a deterministic pseudo-noise, so that a fit does not end at zero cost.
fn with_noise(y: &[f64], i: usize) -> Vec<f64> {
    y.iter()
        .enumerate()
        .map(|(j, v)| v + 1e-3 * ((j * 7 + i * 13) as f64).sin())
        .collect()
}

#[test]
fn refinement_is_bitwise_identical_across_thread_counts() {
    let terms = terms_of(&[Offset, Viscous, SensorLag]);
    let truth = [0.8, 0.2, 1.6, 0.3, 0.05, 0.01];
    let m = 6;
    let ys: Vec<Vec<f64>> = (0..m)
        .map(|i| {
            let exc = Excitation {
                samples: 64,
                amplitude: 1.0 + (i % 2) as f64,
                frequency: 1.0 + i as f64,
                grid_phase: 0.3 * i as f64,
            };
            let y = augmented_output(&exc, &terms, &truth, 1.0, 0.5 + 0.1 * i as f64, 4)
                .unwrap()
                .y;
            with_noise(&y, i)
        })
        .collect();
    let exps: Vec<AugExperiment> = (0..m)
        .map(|i| AugExperiment {
            ybar: &ys[i],
            amplitude: 1.0 + (i % 2) as f64,
            frequency: 1.0 + i as f64,
            grid_phase: 0.3 * i as f64,
            weight: 1e6,
            waveform: &[],
            input: Default::default(),
            substeps: None,
        })
        .collect();
    let start = [0.7, 0.25, 1.8, 0.2, 0.06, 0.02];
    let gains = vec![1.1; m];
    let phases: Vec<f64> = (0..m).map(|i| 0.55 + 0.1 * i as f64).collect();
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| {
                augmented_refine(&exps, &terms, &start, &gains, &phases, &Options::default())
                    .unwrap()
            })
    };
    let (a, b) = (run(1), run(2));
    assert!(a.converged && a.iterations > 3);
    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&a.shared), bits(&b.shared));
    assert_eq!(bits(&a.gains), bits(&b.gains));
    assert_eq!(a.cost.to_bits(), b.cost.to_bits());
    assert_eq!(bits(a.fisher.as_slice()), bits(b.fisher.as_slice()));
    for (x, y) in a.shared.iter().zip(&truth) {
        assert!((x - y).abs() < 0.05 * y.abs(), "{:?}", a.shared);
    }
}

#[test]
fn each_experiment_is_evaluated_at_its_own_substep_count() {
    // A coarse grid (16 samples) and a fine one (96): the outputs at the minimiser are the model's
    // at each experiment's own count, bit for bit, and a count equal to the refinement's is the
    // refinement's default.
    let terms = terms_of(&[Offset, Viscous]);
    let truth = [0.8, 0.2, 1.6, 0.3, 0.05];
    let sizes = [16usize, 96];
    let excs: Vec<Excitation> = sizes
        .iter()
        .enumerate()
        .map(|(i, &p)| Excitation {
            samples: p,
            amplitude: 1.0 + i as f64,
            frequency: 1.0 + 2.0 * i as f64,
            grid_phase: 0.2 + 0.3 * i as f64,
        })
        .collect();
    let ys: Vec<Vec<f64>> = excs
        .iter()
        .enumerate()
        .map(|(i, exc)| {
            let y = augmented_output(exc, &terms, &truth, 1.1, 0.5, 64)
                .unwrap()
                .y;
            with_noise(&y, i)
        })
        .collect();
    let exps_with = |counts: [Option<usize>; 2]| -> Vec<AugExperiment> {
        (0..2)
            .map(|i| AugExperiment {
                ybar: &ys[i],
                amplitude: excs[i].amplitude,
                frequency: excs[i].frequency,
                grid_phase: excs[i].grid_phase,
                weight: 1e6,
                waveform: &[],
                input: Default::default(),
                substeps: counts[i],
            })
            .collect()
    };
    let start = [0.7, 0.25, 1.8, 0.2, 0.06];
    let opts = Options::default();
    let fit = |counts| {
        augmented_refine(
            &exps_with(counts),
            &terms,
            &start,
            &[1.0; 2],
            &[0.45; 2],
            &opts,
        )
        .unwrap()
    };
    let own = fit([Some(8), Some(2)]);
    for (i, count) in [8, 2].into_iter().enumerate() {
        let y = augmented_output(
            &excs[i],
            &terms,
            &own.shared,
            own.gains[i],
            own.phases[i],
            count,
        )
        .unwrap()
        .y;
        assert_eq!(y, own.outputs[i], "experiment {i} at {count} substeps");
    }
    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    let same = fit([Some(opts.substeps), None]);
    let default = fit([None, None]);
    assert_eq!(bits(&same.shared), bits(&default.shared));
    assert_eq!(same.cost.to_bits(), default.cost.to_bits());
    // Other counts move the minimiser, by the integration error only.
    assert_ne!(bits(&own.shared), bits(&default.shared));
    for (a, b) in own.shared.iter().zip(&default.shared) {
        assert!(
            (a - b).abs() < 1e-3 * b.abs().max(1e-2),
            "{:?} {:?}",
            own.shared,
            default.shared
        );
    }
}

#[test]
fn refinement_reads_the_input_columns_it_computed_once() {
    // The refinement computes each experiment's measured-input columns once (`InputColumns`); its
    // outputs at the minimiser are `augmented_output_with`'s, which computes them afresh, bit for
    // bit, for every term that reads them on a distorted input with a mean, and for a model with
    // none of them (the columns then not computed at all).
    let harmonics = [0.08, -0.03, 0.02, 0.01, -0.015, 0.004];
    let input = MeasuredInput {
        harmonics: &harmonics,
        dc: 0.1,
    };
    for (kinds, truth, start) in [
        (
            vec![Stiffness, Viscous, Inertia, Coulomb],
            vec![0.8, 0.2, 1.6, 0.3, 0.05, 0.01, 0.1],
            vec![0.7, 0.25, 1.8, 0.2, 0.06, 0.02, 0.05],
        ),
        (
            vec![Offset],
            vec![0.8, 0.2, 1.6, 0.3],
            vec![0.7, 0.25, 1.8, 0.2],
        ),
    ] {
        let terms = terms_of(&kinds);
        let excs: Vec<Excitation> = (0..3)
            .map(|i| Excitation {
                samples: 48 + 16 * i,
                amplitude: 1.0 + 0.5 * i as f64,
                frequency: 1.0 + i as f64,
                grid_phase: 0.3 * i as f64,
            })
            .collect();
        let ys: Vec<Vec<f64>> = excs
            .iter()
            .enumerate()
            .map(|(i, exc)| {
                let y = augmented_output_with(exc, &[], input, &terms, &truth, 1.1, 0.5, 4)
                    .unwrap()
                    .y;
                with_noise(&y, i)
            })
            .collect();
        let exps: Vec<AugExperiment> = excs
            .iter()
            .zip(&ys)
            .map(|(exc, y)| AugExperiment {
                ybar: y,
                amplitude: exc.amplitude,
                frequency: exc.frequency,
                grid_phase: exc.grid_phase,
                weight: 1e6,
                waveform: &[],
                input,
                substeps: None,
            })
            .collect();
        let opts = Options::default();
        let fit = augmented_refine(&exps, &terms, &start, &[1.0; 3], &[0.45; 3], &opts).unwrap();
        assert!(fit.iterations > 3, "{kinds:?}");
        for (i, exc) in excs.iter().enumerate() {
            let y = augmented_output_with(
                exc,
                &[],
                input,
                &terms,
                &fit.shared,
                fit.gains[i],
                fit.phases[i],
                opts.substeps,
            )
            .unwrap()
            .y;
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&y), bits(&fit.outputs[i]), "{kinds:?}, experiment {i}");
        }
    }
}

#[test]
fn refinement_rejects_bad_input_by_name() {
    let y = vec![0.0; 16];
    let terms = terms_of(&[SensorLag]);
    let exps = [AugExperiment {
        ybar: &y,
        amplitude: 1.0,
        frequency: 1.0,
        grid_phase: 0.0,
        weight: 1.0,
        waveform: &[],
        input: Default::default(),
        substeps: None,
    }];
    let go = |shared: &[f64], opts: &Options| {
        augmented_refine(&exps, &terms, shared, &[1.0], &[0.0], opts).unwrap_err()
    };
    let ok = Options::default();
    assert!(go(&[0.5, 0.1, 1.5], &ok).to_string().contains("need 4"));
    assert!(go(&[0.5, 0.1, 1.5, -0.1], &ok).to_string().contains(">= 0"));
    let bad = Options {
        mu_lo: 2.0,
        mu_hi: 1.5,
        ..ok
    };
    assert!(go(&[0.5, 0.1, 1.7, 0.1], &bad)
        .to_string()
        .contains("mu bracket"));
}
