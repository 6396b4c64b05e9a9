//! Criterion benches of the numerical core: one RK4 step of the Wiener system (1a)-(2a), periodic
//! averaging (4a-b), one evaluation of the SLS cost (21), and the whole golden-section search
//! (24a-b).

use std::f64::consts::PI;
use std::hint::black_box;
use std::time::Duration;

use _core::average::periodic_average;
use _core::bouc_wen::BoucWen;
use _core::estimate::{max_harmonics, spectral_derivative};
use _core::linear::TransferFunction;
use _core::path_loop::path_loop;
use _core::simulate::{rk4_step_count, simulate, Input};
use _core::solve::{sls_search, SlsProblem, GOLDEN_MAX_ITER};
use _core::steady::steady_loop;
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

criterion_group! {
    name = benches;
    config = Criterion::default()
        .sample_size(20)
        .measurement_time(Duration::from_secs(2))
        .warm_up_time(Duration::from_millis(500));
    targets = bench_rk4, bench_average, bench_sls, bench_path_loop
}
criterion_main!(benches);
