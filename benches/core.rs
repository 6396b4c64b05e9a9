//! Criterion benches of the numerical core: one RK4 step of the Wiener system (1a)-(2a), periodic
//! averaging (4a-b), one evaluation of the SLS cost (21), and the whole golden-section search
//! (24a-b); the default method's hot path (issue #8): one steady loop with its sensitivities
//! (`rust/steady.rs`) and the joint Levenberg-Marquardt refinement over 10 experiments
//! (`rust/refine.rs`), serially and as 16 parallel starts (`rust/multistart.rs`); the lab
//! preprocessing kernels (`rust/lab.rs`) on a 20,000-sample record.

use std::f64::consts::PI;
use std::hint::black_box;
use std::time::Duration;

use _core::augmented::{augmented_output, augmented_refine, AugExperiment, Excitation};
use _core::average::periodic_average;
use _core::bouc_wen::BoucWen;
use _core::estimate::{max_harmonics, spectral_derivative};
use _core::lab::fit::{harmonic_fit_at, harmonic_nls};
use _core::lab::{cholesky_upper, harmonic_gauss_newton, harmonic_moments, harmonic_rss};
use _core::linear::TransferFunction;
use _core::multistart::refine_many;
use _core::path_loop::path_loop;
use _core::refine::{refine, Experiment, Options, Params};
use _core::simulate::{rk4_step_count, simulate, Input};
use _core::solve::{sls_search, SlsProblem, GOLDEN_MAX_ITER};
use _core::steady::steady_loop;
use _core::terms::{TermKind, Terms};
use criterion::{criterion_group, criterion_main, Criterion, Throughput};

const P: usize = 1024;
const OMEGA: f64 = 2.0;
const U: f64 = 1.3;
const PHI: f64 = 0.9;

fn bouc_wen() -> BoucWen {
    BoucWen::new(1.0, 0.8, 0.3, 2.5, 0.0).expect("valid Bouc-Wen parameters")
}

/// One averaged period of a simulated loop and its spectral derivative.
fn loop_data() -> (Vec<f64>, Vec<f64>) {
    let tf = TransferFunction::new(&[1.0], &[1.0], PHI / OMEGA).expect("valid G");
    let dt = 2.0 * PI / OMEGA / P as f64;
    let input = Input::Sine {
        amplitude: U,
        omega: OMEGA,
    };
    let sim = simulate(&tf, &bouc_wen(), input, dt, 6 * P, 4).expect("simulation");
    let ybar = periodic_average(&sim.w, P, 4, 2).expect("average");
    let ydot = spectral_derivative(&ybar, OMEGA, max_harmonics(P)).expect("derivative");
    (ybar, ydot)
}

fn bench_rk4(c: &mut Criterion) {
    // Second-order, lightly damped G with a delay: 2 states + w.
    let tf = TransferFunction::new(&[4.0], &[1.0, 0.8, 4.0], 0.05).expect("valid G");
    let bw = bouc_wen();
    let (n_samples, substeps) = (10_001, 4);
    let input = Input::Sine {
        amplitude: U,
        omega: OMEGA,
    };
    let mut group = c.benchmark_group("simulate");
    group.throughput(Throughput::Elements(
        rk4_step_count(n_samples, substeps) as u64
    ));
    let static_gain = TransferFunction::new(&[1.5], &[1.0], 0.05).expect("valid G");
    group.bench_function("rk4_step_static_gain", |b| {
        b.iter(|| {
            simulate(
                black_box(&static_gain),
                black_box(&bw),
                black_box(input),
                black_box(0.01),
                n_samples,
                substeps,
            )
        })
    });
    group.bench_function("rk4_step", |b| {
        b.iter(|| {
            simulate(
                black_box(&tf),
                black_box(&bw),
                black_box(input),
                black_box(0.01),
                n_samples,
                substeps,
            )
        })
    });
    group.finish();
}

fn bench_average(c: &mut Criterion) {
    let y: Vec<f64> = (0..P * 200).map(|i| (i as f64 * 0.37).sin()).collect();
    c.bench_function("periodic_average", |b| {
        b.iter(|| periodic_average(black_box(&y), P, 0, 200))
    });
}

/// The lab kernels on the bench_pipeline record size: 20,000 samples at 317.3 samples per period;
/// the moments and the Gram factor at K = 200 (the synchronous average's largest), the frequency
/// fit's terms at K = 1 (the sine fit), and the whole fits built on them.
fn bench_lab(c: &mut Criterion) {
    const N: usize = 20_000;
    const K: usize = 200;
    let tau: Vec<f64> = (0..N).map(|i| (i as f64 - 0.5 * N as f64) * 1e-3).collect();
    let omega = 2.0 * PI / (317.3e-3);
    let theta: Vec<f64> = tau
        .iter()
        .map(|t| (omega * t).rem_euclid(2.0 * PI))
        .collect();
    let x: Vec<f64> = theta.iter().map(|t| 0.2 + (t + 0.4).cos()).collect();
    c.bench_function("harmonic_moments_20000_k200", |b| {
        b.iter(|| harmonic_moments(black_box(&theta), &x, K))
    });
    let coef = [0.2, 0.9, -0.4];
    c.bench_function("harmonic_gauss_newton_20000_k1", |b| {
        b.iter(|| harmonic_gauss_newton(black_box(&theta), &tau, &x, &coef))
    });
    c.bench_function("harmonic_rss_20000_k1", |b| {
        b.iter(|| harmonic_rss(black_box(&theta), &x, &coef))
    });
    // A unit-diagonal Gram matrix with small off-diagonal terms, as the harmonics over many periods.
    let m = 2 * K + 1;
    let gram: Vec<f64> = (0..m * m)
        .map(|i| {
            let (r, c) = (i / m, i % m);
            if r == c {
                1.0
            } else {
                1e-3 / (1.0 + r.abs_diff(c) as f64)
            }
        })
        .collect();
    c.bench_function("cholesky_upper_401", |b| {
        b.iter(|| cholesky_upper(black_box(&gram), m))
    });
    // Whole fits, one call each: the synchronous average's (K = 200, phases from omega and the
    // times) and the sine analysis's frequency Gauss-Newton from 1e-4 off.
    c.bench_function("harmonic_fit_20000_k200", |b| {
        b.iter(|| harmonic_fit_at(black_box(&tau), Some(omega), &x, K))
    });
    c.bench_function("harmonic_nls_20000_k1", |b| {
        b.iter(|| harmonic_nls(black_box(&tau), &x, omega * (1.0 + 1e-4), 1e-3, 1))
    });
}

fn bench_sls(c: &mut Criterion) {
    let (ybar, ydot) = loop_data();
    let problem = SlsProblem::new(&ybar, &ydot, U, OMEGA, PHI).expect("valid SLS inputs");
    c.bench_function("sls_cost", |b| b.iter(|| problem.cost(black_box(2.5))));
    c.bench_function("sls_search", |b| {
        b.iter(|| sls_search(black_box(&problem), 1.0, 10.0, 1e-8, GOLDEN_MAX_ITER))
    });
}

/// The steady loop along the input path (design.md 9.2), called (LM iterations x experiments)
/// times per augmented fit: P = 256, 4 substeps, with asymmetry and play; the plain half-cycle
/// loop (7.2) at the same grid for comparison.
fn bench_path_loop(c: &mut Criterion) {
    let (p, substeps) = (256, 4);
    c.bench_function("path_loop_p256_sub4", |b| {
        b.iter(|| {
            path_loop(
                black_box(1.4),
                black_box(0.7),
                black_box(0.25),
                black_box(1.8),
                black_box(0.2),
                black_box(0.1),
                black_box(PHI),
                p,
                substeps,
            )
        })
    });
    c.bench_function("steady_loop_p256_sub4", |b| {
        b.iter(|| {
            steady_loop(
                black_box(1.4),
                black_box(0.7),
                black_box(0.25),
                black_box(1.8),
                black_box(PHI),
                p,
                substeps,
            )
        })
    });
}

/// One augmented refinement (design.md 9.3) on 10 experiments (P = 256, 5 frequencies x 2
/// amplitudes) with the terms [offset, viscous], from a start 10-20 % off, the data made by the
/// model itself plus a deterministic pseudo-noise; and one model output with its Jacobian.
fn bench_augmented(c: &mut Criterion) {
    let (p, m) = (256, 10);
    let names = [TermKind::Offset.name(), TermKind::Viscous.name()];
    let terms = Terms::parse(&names).expect("valid terms");
    let truth = [0.8, 0.2, 1.6, 0.3, 0.05];
    let exc: Vec<Excitation> = (0..m)
        .map(|i| Excitation {
            samples: p,
            amplitude: if i % 2 == 0 { 1.0 } else { 2.0 },
            frequency: 1.0 + (i / 2) as f64 * 2.0,
            grid_phase: 0.37 * i as f64,
        })
        .collect();
    let gains: Vec<f64> = (0..m).map(|i| 1.0 / (1.0 + 0.1 * i as f64)).collect();
    let phases: Vec<f64> = (0..m).map(|i| 0.3 + 0.1 * i as f64).collect();
    let ys: Vec<Vec<f64>> = (0..m)
        .map(|i| {
            let y = augmented_output(&exc[i], &terms, &truth, gains[i], phases[i], 8)
                .expect("model output")
                .y;
            y.iter()
                .enumerate()
                .map(|(j, v)| v + 1e-3 * ((7 * j + 13 * i) as f64).sin())
                .collect()
        })
        .collect();
    let exps: Vec<AugExperiment> = (0..m)
        .map(|i| AugExperiment {
            ybar: &ys[i],
            amplitude: exc[i].amplitude,
            frequency: exc[i].frequency,
            grid_phase: exc[i].grid_phase,
            weight: 1e6,
            waveform: &[],
            input: Default::default(),
            substeps: None,
        })
        .collect();
    let start = [0.7, 0.25, 1.8, 0.25, 0.06];
    let g0: Vec<f64> = gains.iter().map(|g| g * 1.1).collect();
    let ph0: Vec<f64> = phases.iter().map(|v| v + 0.05).collect();
    let opts = Options::default();
    c.bench_function("augmented_refine_m10_p256_offset_viscous", |b| {
        b.iter(|| augmented_refine(black_box(&exps), &terms, &start, &g0, &ph0, &opts))
    });
    c.bench_function("augmented_output_p256_offset_viscous", |b| {
        b.iter(|| augmented_output(black_box(&exc[3]), &terms, &truth, 0.9, 0.4, 4))
    });
}

/// Samples per period of the refinement benches (about what identify() averages lab data onto).
const P_REFINE: usize = 1000;
/// Experiments of the joint refinement bench.
const M_REFINE: usize = 10;

fn bench_steady_loop(c: &mut Criterion) {
    c.bench_function("steady_loop_p1000", |b| {
        b.iter(|| steady_loop(black_box(1.4), 0.8, 0.2, 1.6, 0.7, P_REFINE, 4))
    });
}

/// Ten noise-free loops of one Bouc-Wen element at amplitudes 0.6..2.4 and phases 0.3..1.2.
fn refine_data() -> (Vec<Vec<f64>>, Vec<f64>) {
    let amps: Vec<f64> = (0..M_REFINE).map(|i| 0.6 + 0.2 * i as f64).collect();
    let ys = amps
        .iter()
        .enumerate()
        .map(|(i, a)| {
            steady_loop(0.9 * a, 0.8, 0.2, 1.6, 0.3 + 0.1 * i as f64, P_REFINE, 4)
                .expect("valid loop")
                .w
        })
        .collect();
    (ys, amps)
}

fn bench_refine(c: &mut Criterion) {
    let (ys, amps) = refine_data();
    let exps: Vec<Experiment> = ys
        .iter()
        .zip(&amps)
        .map(|(y, &amplitude)| Experiment {
            ybar: y,
            amplitude,
            weight: 1.0,
        })
        .collect();
    // A start off in every parameter, as the separable estimates typically are.
    let start = Params {
        beta: 1.0,
        gamma: 0.1,
        mu: 1.9,
        gains: vec![0.8; M_REFINE],
        phases: (0..M_REFINE).map(|i| 0.25 + 0.1 * i as f64).collect(),
    };
    let opts = Options::default();
    c.bench_function("refine_10x1000", |b| {
        b.iter(|| refine(black_box(&exps), black_box(&start), &opts))
    });
    // 16 screening starts of 25 iterations (the generic restarts of identify), 1 thread vs all.
    let starts: Vec<Params> = (0..16)
        .map(|k| Params {
            beta: 0.5 + 0.1 * k as f64,
            gamma: if k % 2 == 0 { 0.2 } else { -0.2 },
            mu: 1.15 + 0.25 * (k / 4) as f64,
            gains: vec![1.2; M_REFINE],
            phases: (0..M_REFINE).map(|i| 0.1 * i as f64).collect(),
        })
        .collect();
    let screen = Options {
        max_iter: 25,
        ..Options::default()
    };
    for threads in [1, 0] {
        let name = if threads == 1 {
            "refine_many_16_starts_1_thread"
        } else {
            "refine_many_16_starts_all_cores"
        };
        c.bench_function(name, |b| {
            b.iter(|| refine_many(black_box(&exps), &starts, &screen, None, threads))
        });
    }
}

criterion_group! {
    name = benches;
    config = Criterion::default()
        .sample_size(20)
        .measurement_time(Duration::from_secs(2))
        .warm_up_time(Duration::from_millis(500));
    targets = bench_rk4, bench_average, bench_sls, bench_steady_loop, bench_refine, bench_path_loop,
        bench_augmented, bench_lab
}
criterion_main!(benches);
