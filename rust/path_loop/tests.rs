//! Unit tests of the path loop.

use super::*;
use crate::steady::steady_loop;
use std::f64::consts::PI;

#[allow(clippy::too_many_arguments)]
fn pl(
    a: f64,
    beta: f64,
    gamma: f64,
    mu: f64,
    delta: f64,
    b: f64,
    phi: f64,
    p: usize,
    sub: usize,
) -> PathLoop {
    path_loop(a, beta, gamma, mu, delta, b, phi, p, sub).unwrap()
}

/// Largest difference of w, and largest relative one of the 5 common Jacobian columns.
fn diff_to_steady(l: &PathLoop, w: &[f64], jac: &[[f64; 5]]) -> (f64, f64) {
    let dw =
        l.w.iter()
            .zip(w)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
    let dj = l
        .jac
        .iter()
        .zip(jac)
        .flat_map(|(r, q)| (0..5).map(move |k| (r[k] - q[k]).abs() / (1.0 + q[k].abs())))
        .fold(0.0, f64::max);
    (dw, dj)
}

#[test]
fn plain_case_agrees_with_the_half_cycle_steady_loop() {
    // Two different O(h^4) discretisations (RK4 in theta on the folded lattice vs RK4 in xp
    // between nodes) of the same loop. With mu = 3, |w|^mu is C^3 through w = 0 and both keep
    // their order: the difference must shrink about 16x from 16 to 32 substeps (at least 8x
    // is asserted) and be at the measured RK4 error level (w ~ 1e-11, Jacobian ~ 1e-9 at 32
    // substeps on P = 64), with a 5x margin.
    let (a, beta, gamma, mu, phi, p) = (1.4, 0.7, 0.25, 3.0, 0.9, 64);
    let mut prev = (f64::INFINITY, f64::INFINITY);
    for sub in [16, 32] {
        let l = pl(a, beta, gamma, mu, 0.0, 0.0, phi, p, sub);
        let s = steady_loop(a, beta, gamma, mu, phi, p, sub).unwrap();
        let d = diff_to_steady(&l, &s.w, &s.jac);
        assert!(
            d.0 < prev.0 / 8.0 && d.1 < prev.1 / 8.0,
            "sub {sub}: {d:?} vs {prev:?}"
        );
        prev = d;
    }
    assert!(prev.0 < 5e-11 && prev.1 < 5e-9, "{prev:?}");
    // mu < 2: |w|^(mu-2) is singular where w crosses 0, so RK4 drops to about order mu + 1
    // on those two steps; at 64 substeps both are within ~2e-10 of the limit (w) and
    // ~3e-7 (Jacobian, whose rate carries |w|^(mu-1)): tolerance 5x.
    let l = pl(a, beta, gamma, 1.8, 0.0, 0.0, -2.0, 48, 64);
    let s = steady_loop(a, beta, gamma, 1.8, -2.0, 48, 64).unwrap();
    let d = diff_to_steady(&l, &s.w, &s.jac);
    assert!(d.0 < 1e-9 && d.1 < 2e-6, "{d:?}");
}

#[test]
fn jacobian_matches_central_differences() {
    // Central differences of the same discrete map: truncation (h^2 w''' ~ 1e-10) plus the
    // shooting's tolerance 1e-13 w_b / (1 - Phi) on each call divided by 2h (~1e-8 for
    // h = 1e-5), so 1e-6 (1 + |fd|) is a test that a wrong chain-rule term (O(1)) fails.
    let sets: [[f64; 7]; 5] = [
        // [beta, gamma, mu, A, phi, delta, b]
        [0.7, 0.25, 1.8, 1.4, 0.9, 0.2, 0.15],
        [0.9, -0.3, 2.5, -1.1, 2.0, -0.35, 0.3],
        [0.5, 0.5, 1.3, 3.0, -1.0, 0.45, 0.5],
        [1.0, 0.2, 2.0, 0.3, 4.0, 0.5, 0.05],
        [0.6, 0.1, 3.5, -2.2, 0.3, 0.0, 1.1],
    ];
    let p = 40;
    let sub = 3;
    let run = |q: &[f64; 7]| pl(q[3], q[0], q[1], q[2], q[5], q[6], q[4], p, sub);
    for q in sets {
        let base = run(&q);
        for k in 0..7 {
            let h = 1e-5 * q[k].abs().max(1.0);
            let (mut up, mut dn) = (q, q);
            up[k] += h;
            dn[k] -= h;
            let (lu, ld) = (run(&up), run(&dn));
            for j in 0..p {
                let fd = (lu.w[j] - ld.w[j]) / (2.0 * h);
                let an = base.jac[j][k];
                assert!(
                    (fd - an).abs() < 1e-6 * (1.0 + fd.abs()),
                    "set {q:?}, column {k}, sample {j}: fd {fd} vs {an}"
                );
            }
        }
    }
}

#[test]
fn pinched_jacobian_matches_central_differences_and_zero_pinch_is_the_plain_loop() {
    let sets: [[f64; 8]; 3] = [
        // [beta, gamma, mu, A, phi, delta, b, zeta1]
        [0.7, 0.25, 1.8, 1.4, 0.9, 0.2, 0.15, 0.5],
        [0.9, -0.3, 2.5, -1.1, 2.0, -0.35, 0.05, 0.3],
        [0.5, 0.5, 1.3, 3.0, -1.0, 0.0, 0.5, 0.8],
    ];
    let (p, sub) = (40, 6);
    let run = |q: &[f64; 8]| {
        path_loop_pinched(q[3], q[0], q[1], q[2], q[5], q[6], q[4], q[7], None, p, sub).unwrap()
    };
    for q in sets {
        let base = run(&q);
        let plain = pl(q[3], q[0], q[1], q[2], q[5], q[6], q[4], p, sub);
        let mut zero = q;
        zero[7] = 0.0;
        let z = run(&zero);
        assert_eq!(z.w, plain.w);
        // At zeta1 = 0 the column is still d w / d zeta1 (the diagnosis starts there).
        assert!(z.jac.iter().any(|r| r[PD_PINCH].abs() > 1e-3));
        assert!(base
            .w
            .iter()
            .zip(&plain.w)
            .any(|(a, b)| (a - b).abs() > 1e-3));
        for k in 0..8 {
            let col = if k == 7 { PD_PINCH } else { k };
            let h = 1e-5 * q[k].abs().max(1.0);
            let (mut up, mut dn) = (q, q);
            up[k] += h;
            dn[k] -= h;
            let (lu, ld) = (run(&up), run(&dn));
            for j in 0..p {
                let fd = (lu.w[j] - ld.w[j]) / (2.0 * h);
                let an = base.jac[j][col];
                assert!(
                    (fd - an).abs() < 1e-6 * (1.0 + fd.abs()),
                    "set {q:?}, column {k}, sample {j}: fd {fd} vs {an}"
                );
            }
        }
    }
    let e = path_loop_pinched(1.0, 0.7, 0.3, 1.8, 0.0, 0.0, 0.0, 1.0, None, p, sub).unwrap_err();
    assert!(e.to_string().contains("zeta1"), "{e}");
}

#[test]
fn asymmetric_saturation_levels() {
    // Far beyond saturation, loading drives w to the root of h = 0 on each side:
    // (beta + gamma + delta)^(-1/mu) ascending with w > 0, -(beta + gamma - delta)^(-1/mu)
    // descending with w < 0; at A = 60 the gap has decayed like exp(-120 mu c w^(mu-1)),
    // so only the RK4 error (< 1e-9 at 16 substeps) remains.
    let (beta, gamma, delta, mu) = (0.6, 0.3, 0.25, 2.0);
    let l = pl(60.0, beta, gamma, mu, delta, 0.0, 0.0, 256, 16);
    let max = l.w.iter().copied().fold(f64::MIN, f64::max);
    let min = l.w.iter().copied().fold(f64::MAX, f64::min);
    let top = (beta + gamma + delta).powf(-1.0 / mu);
    let bottom = -(beta + gamma - delta).powf(-1.0 / mu);
    assert!((max - top).abs() < 1e-9, "{max} vs {top}");
    assert!((min - bottom).abs() < 1e-9, "{min} vs {bottom}");
    // Symmetric (delta = 0): both sides saturate at w_b itself, the edge of the shooting's
    // bracket.
    let sym = pl(60.0, beta, gamma, mu, 0.0, 0.0, 0.0, 256, 16);
    let wb = (beta + gamma).powf(-1.0 / mu);
    let max = sym.w.iter().copied().fold(f64::MIN, f64::max);
    let min = sym.w.iter().copied().fold(f64::MAX, f64::min);
    assert!(
        (max - wb).abs() < 1e-9 && (min + wb).abs() < 1e-9,
        "{max} {min} {wb}"
    );
    // Swapping the sign of delta and of x mirrors the loop: w -> -w.
    let m = pl(-60.0, beta, gamma, mu, -delta, 0.0, 0.0, 256, 16);
    for (a, b) in l.w.iter().zip(&m.w) {
        assert!((a + b).abs() < 1e-12, "{a} vs {b}");
    }
}

#[test]
fn play_dwells_and_shifts_the_plain_loop() {
    let (a, beta, gamma, mu, delta, b, phi, p, sub) = (1.5, 0.8, 0.1, 2.5, 0.15, 0.3, 0.4, 64, 32);
    let l = pl(a, beta, gamma, mu, delta, b, phi, p, sub);
    let (mut dwell_top, mut dwell_bottom, mut active) = (vec![], vec![], 0);
    for j in 0..p {
        let zeta = (2.0 * PI * j as f64 / p as f64 - phi).rem_euclid(2.0 * PI);
        let x = a * zeta.cos();
        let descending = zeta <= PI;
        if descending && x >= a - 2.0 * b {
            dwell_top.push(l.w[j]);
            continue;
        }
        if !descending && x <= -a + 2.0 * b {
            dwell_bottom.push(l.w[j]);
            continue;
        }
        // Active: xp = x -+ b moves; the plain loop of amplitude a - b, sampled where its
        // x equals this xp on the same branch, has the same w (rate independence). Both
        // are RK4 at 32 substeps per segment or finer (error < 1e-10 here): tolerance 1e-9.
        active += 1;
        let xp = if descending { x + b } else { x - b };
        let c = (xp / (a - b)).clamp(-1.0, 1.0).acos();
        let zeta_plain = if descending { c } else { 2.0 * PI - c };
        let plain = pl(a - b, beta, gamma, mu, delta, 0.0, -zeta_plain, 4, 256);
        assert!(
            (plain.w[0] - l.w[j]).abs() < 1e-9,
            "sample {j}: {} vs {}",
            l.w[j],
            plain.w[0]
        );
    }
    assert!(dwell_top.len() >= 2 && dwell_bottom.len() >= 2 && active > 20);
    // Inside a dwell xp does not move, so w does not either (bit for bit: the map is the
    // identity there).
    for d in [&dwell_top, &dwell_bottom] {
        assert!(d.iter().all(|&v| v == d[0]), "{d:?}");
    }
}

#[test]
fn periodic_in_phase_and_sign_of_the_amplitude() {
    let (beta, gamma, mu, delta, b, p) = (0.7, 0.2, 1.7, -0.3, 0.2, 50);
    let l = pl(1.3, beta, gamma, mu, delta, b, 0.77, p, 4);
    // One sample later in phase is the same node set: the loop rotates by one sample.
    let r = pl(
        1.3,
        beta,
        gamma,
        mu,
        delta,
        b,
        0.77 + 2.0 * PI / p as f64,
        p,
        4,
    );
    // A full turn of phi, and -A half a turn later, are the same x.
    let t = pl(1.3, beta, gamma, mu, delta, b, 0.77 - 2.0 * PI, p, 4);
    let n = pl(-1.3, beta, gamma, mu, delta, b, 0.77 + PI, p, 4);
    for j in 0..p {
        assert!((r.w[(j + 1) % p] - l.w[j]).abs() < 1e-12);
        assert!((t.w[j] - l.w[j]).abs() < 1e-12);
        assert!((n.w[j] - l.w[j]).abs() < 1e-12);
        // d/dA flips with the sign of A; the other columns agree.
        for k in 0..7 {
            let s = if k == PD_AMPLITUDE { -1.0 } else { 1.0 };
            assert!(
                (s * n.jac[j][k] - l.jac[j][k]).abs() < 1e-9 * (1.0 + l.jac[j][k].abs()),
                "sample {j} column {k}"
            );
        }
    }
    // Odd P works too.
    assert_eq!(pl(1.3, beta, gamma, mu, delta, b, 0.77, 7, 4).w.len(), 7);
}

#[test]
fn multiple_and_single_shooting_find_the_same_loop() {
    // The same discrete fixed point, reached two ways: the joins of the four pieces meet to
    // 1e-13 w_b, so w agrees to a few 1e-13 and the Jacobian to rounding of the chain rule.
    for (args, p) in [
        ((1.4, 0.7, 0.25, 1.8, 0.2, 0.15, 0.9), 64),
        ((-2.5, 0.9, -0.3, 2.5, -0.35, 0.6, 2.0), 37),
        ((0.2, 1.0, 0.2, 1.2, 0.5, 0.0, -1.0), 16),
    ] {
        let m = path_loop_with(args, None, None, p, 4, true).unwrap();
        let s = path_loop_with(args, None, None, p, 4, false).unwrap();
        for j in 0..p {
            assert!((m.w[j] - s.w[j]).abs() < 1e-12, "{args:?} sample {j}");
            for k in 0..7 {
                let (a, b) = (m.jac[j][k], s.jac[j][k]);
                assert!(
                    (a - b).abs() < 1e-9 * (1.0 + b.abs()),
                    "{args:?} {j} {k}: {a} {b}"
                );
            }
        }
    }
}

type Args = (f64, f64, f64, f64, f64, f64, f64, usize, usize);

fn call(f: &dyn Fn(&mut Args)) -> Result<PathLoop> {
    let mut a: Args = (1.0, 0.5, 0.2, 1.5, 0.1, 0.1, 0.0, 64, 4);
    f(&mut a);
    path_loop(a.0, a.1, a.2, a.3, a.4, a.5, a.6, a.7, a.8)
}

#[test]
fn every_bad_input_is_a_named_error() {
    assert!(call(&|_| {}).is_ok());
    for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        let setters: [&dyn Fn(&mut Args); 7] = [
            &|a| a.0 = bad,
            &|a| a.1 = bad,
            &|a| a.2 = bad,
            &|a| a.3 = bad,
            &|a| a.4 = bad,
            &|a| a.5 = bad,
            &|a| a.6 = bad,
        ];
        for f in setters {
            let r = call(f);
            assert!(matches!(r, Err(CoreError::NonFinite(_))), "{r:?}");
        }
    }
    let invalid: [&dyn Fn(&mut Args); 8] = [
        &|a| a.3 = 1.0,
        &|a| a.3 = 0.5,
        &|a| a.4 = 0.7,
        &|a| a.4 = -0.7,
        &|a| a.5 = -1e-3,
        &|a| a.8 = 0,
        &|a| a.7 = 1 << 25,
        &|a| {
            a.7 = 1 << 20;
            a.8 = 1 << 20
        },
    ];
    for f in invalid {
        let r = call(f);
        assert!(matches!(r, Err(CoreError::InvalidParameter(_))), "{r:?}");
    }
    let zero: [&dyn Fn(&mut Args); 4] = [&|a| a.0 = 0.0, &|a| a.5 = 1.0, &|a| a.5 = 2.0, &|a| {
        a.0 = -0.5;
        a.5 = 0.5
    }];
    for f in zero {
        let r = call(f);
        assert!(matches!(r, Err(CoreError::ZeroAmplitude(_))), "{r:?}");
    }
    let r = call(&|a| a.7 = 3);
    assert!(matches!(r, Err(CoreError::InsufficientData(_))), "{r:?}");
    // beta < 0 with beta + gamma > 0: unloading runs away at large amplitude, so there is
    // no periodic loop; the shooting says so instead of returning garbage.
    let r = path_loop(20.0, -0.4, 1.0, 2.0, 0.0, 0.0, 0.0, 64, 4);
    assert!(matches!(r, Err(CoreError::NotConverged(_))), "{r:?}");
    // A bound that overflows (denormal margin) is refused, not iterated on.
    let r = path_loop(1.0, 5e-324, 0.0, 3.0, 0.0, 0.0, 0.0, 16, 2);
    assert!(matches!(r, Err(CoreError::InvalidParameter(_))), "{r:?}");
    // Parameters at the edge of the float range: an error, never a panic or NaN.
    let r = path_loop(6.1e-96, 4.49e307, 0.0, 4.0, 0.0, 0.0, 0.0, 4, 1);
    assert!(
        matches!(r, Err(CoreError::NonFinite(_) | CoreError::NotConverged(_))),
        "{r:?}"
    );
}

#[test]
fn distorted_waveform_nests_the_sine_and_has_an_exact_lambda_column() {
    // lambda = 0: the reversals land on 0 and pi to rounding, so the loop is the sine's.
    let h = [0.03, -0.02, 0.04, 0.01];
    let wf = |lambda| Waveform {
        lambda,
        harmonics: &h,
    };
    let (p, sub) = (36, 3);
    for a in [1.3, -0.9] {
        let d = path_loop_distorted(a, 0.7, 0.25, 1.8, 0.2, 0.1, 0.4, &wf(0.0), p, sub).unwrap();
        let s = path_loop(a, 0.7, 0.25, 1.8, 0.2, 0.1, 0.4, p, sub).unwrap();
        for j in 0..p {
            assert!((d.w[j] - s.w[j]).abs() < 1e-12);
            for q in 0..7 {
                assert!((d.jac[j][q] - s.jac[j][q]).abs() < 1e-11);
            }
        }
    }
    // d w / d lambda against central differences (as jacobian_matches_central_differences).
    let run =
        |l: f64| path_loop_distorted(1.4, 0.7, 0.25, 1.8, 0.1, 0.15, 0.9, &wf(l), p, sub).unwrap();
    let base = run(1.0);
    let step = 1e-5;
    let (up, dn) = (run(1.0 + step), run(1.0 - step));
    for j in 0..p {
        let fd = (up.w[j] - dn.w[j]) / (2.0 * step);
        let err = (fd - base.jac[j][PD_DISTORT]).abs() / (1.0 + fd.abs());
        assert!(
            err < 1e-6,
            "sample {j}: {fd} vs {}",
            base.jac[j][PD_DISTORT]
        );
    }
    // Too strong a distortion (extra reversals) is a named refusal, not a wrong loop.
    let strong = [0.0, 0.0, 0.5, 0.0];
    let bad = Waveform {
        lambda: 1.0,
        harmonics: &strong,
    };
    let r = path_loop_distorted(1.0, 0.7, 0.25, 1.8, 0.0, 0.0, 0.0, &bad, p, sub);
    assert!(matches!(r, Err(CoreError::InvalidParameter(_))), "{r:?}");
}
