//! Unit tests of the lab kernels (moments, series, residual, Gauss-Newton terms, Cholesky factor).

use super::phasors::uniform_blocks;
use super::*;

#[test]
fn uniform_times_get_block_templates_and_jittered_ones_do_not() {
    let n = 1000;
    let tau: Vec<f64> = (0..n).map(|i| i as f64 * 0.02 - 10.0).collect();
    assert!(uniform_blocks(&tau));
    let omega = 3.7;
    let mut z = Phasors::default();
    let Phases::Cached(re, im, _) = z.fill(Phases::Scaled(omega, &tau)) else {
        unreachable!()
    };
    for (i, t) in tau.iter().enumerate() {
        let (s, c) = (omega * t).sin_cos();
        assert!(
            (re[i] - c).abs() < 1e-13 && (im[i] - s).abs() < 1e-13,
            "sample {i}"
        );
    }
    // A time axis written with 6 decimals (1e-7 s jitter) is not uniform to a few ulp.
    let mut j2: Vec<f64> = tau
        .iter()
        .map(|t| (t * 1e6 + 0.3).round() / 1e6 + 1e-7)
        .collect();
    j2[517] += 3e-7;
    assert!(!uniform_blocks(&j2));
    let Phases::Cached(re, im, _) = z.fill(Phases::Scaled(omega, &j2)) else {
        unreachable!()
    };
    for (i, t) in j2.iter().enumerate() {
        let (s, c) = (omega * t).sin_cos();
        assert!(
            (re[i] - c).abs() < 1e-15 && (im[i] - s).abs() < 1e-15,
            "sample {i}"
        );
    }
}

#[test]
fn templated_moments_match_the_per_sample_sums() {
    for n in [64, 1003, 4099] {
        let tau: Vec<f64> = (0..n).map(|i| i as f64 * 0.01 - 3.0).collect();
        let y: Vec<f64> = tau.iter().map(|t| (7.0 * t).cos() + 0.1 * t).collect();
        let mut z = Phasors::default();
        let phases = z.fill(Phases::Scaled(5.3, &tau));
        let Phases::Cached(re, im, Some(_)) = phases else {
            panic!("a uniform axis gets a template")
        };
        let k = 40;
        let ((mr, mi), (rr, ri)) = moments_of(phases, &y, k);
        let ((er, ei), (sr, si)) = moments_of(Phases::Cached(re, im, None), &y, k);
        for q in 0..=2 * k {
            assert!(
                (mr[q] - er[q]).abs() < 1e-11 * n as f64
                    && (mi[q] - ei[q]).abs() < 1e-11 * n as f64,
                "n = {n}, q = {q}"
            );
        }
        assert_eq!((rr, ri), (sr, si));
    }
}

#[test]
fn moments_match_direct_sums() {
    let n = 37; // not a multiple of LANES: the last block is partial
    let theta: Vec<f64> = (0..n).map(|i| 0.37 * i as f64 + 0.1).collect();
    let y: Vec<f64> = (0..n).map(|i| (i as f64 * 0.7).sin() + 0.2).collect();
    let k = 5;
    let ((mr, mi), (rr, ri)) = harmonic_moments(&theta, &y, k).unwrap();
    for q in 0..=2 * k {
        let (er, ei): (f64, f64) = theta.iter().fold((0.0, 0.0), |acc, t| {
            (acc.0 + (q as f64 * t).cos(), acc.1 + (q as f64 * t).sin())
        });
        assert!(
            (mr[q] - er).abs() < 1e-12 && (mi[q] - ei).abs() < 1e-12,
            "q = {q}"
        );
    }
    for q in 0..=k {
        let (er, ei) = theta.iter().zip(&y).fold((0.0, 0.0), |acc, (t, v)| {
            (
                acc.0 + v * (q as f64 * t).cos(),
                acc.1 - v * (q as f64 * t).sin(),
            )
        });
        assert!(
            (rr[q] - er).abs() < 1e-12 && (ri[q] - ei).abs() < 1e-12,
            "q = {q}"
        );
    }
}

#[test]
fn series_matches_direct_sum_and_validates() {
    let theta: Vec<f64> = (0..21).map(|i| 0.3 * i as f64).collect();
    let coef = [0.5, 1.0, -0.3, 0.2, 0.7, -0.1, 0.05];
    let s = harmonic_series(&theta, &coef).unwrap();
    for (t, v) in theta.iter().zip(&s) {
        let mut e = coef[0];
        for k in 1..=3 {
            e += coef[2 * k - 1] * (k as f64 * t).cos() + coef[2 * k] * (k as f64 * t).sin();
        }
        assert!((v - e).abs() < 1e-13);
    }
    assert!(harmonic_series(&theta, &coef[..6]).is_err());
    assert!(harmonic_moments(&theta, &theta[..3], 2).is_err());
    assert!(harmonic_moments(&theta, &theta, 0).is_err());
    let bad = [f64::NAN, 1.0];
    assert!(matches!(
        harmonic_moments(&bad, &bad, 1),
        Err(CoreError::NonFinite(_))
    ));
}

#[test]
fn gauss_newton_terms_match_direct_sums_and_validate() {
    let n = 29; // a partial last block
    let tau: Vec<f64> = (0..n).map(|i| 0.01 * i as f64 - 0.1).collect();
    let omega = 7.3;
    let theta: Vec<f64> = tau.iter().map(|t| omega * t).collect();
    let x: Vec<f64> = theta.iter().map(|t| 1.2 * (t + 0.3).sin() + 0.1).collect();
    let coef = [0.05, 0.3, 1.1, -0.02, 0.04];
    let (rr, rd, dd, xtd) = harmonic_gauss_newton(&theta, &tau, &x, &coef).unwrap();
    let (mut err, mut erd, mut edd) = (0.0, 0.0, 0.0);
    let mut extd = [0.0; 5];
    for i in 0..n {
        let t = theta[i];
        let mut f = coef[0];
        let mut sl = 0.0;
        for k in 1..=2 {
            let kf = k as f64;
            f += coef[2 * k - 1] * (kf * t).cos() + coef[2 * k] * (kf * t).sin();
            sl += kf * (coef[2 * k] * (kf * t).cos() - coef[2 * k - 1] * (kf * t).sin());
        }
        let d = tau[i] * sl;
        let r = x[i] - f;
        err += r * r;
        erd += r * d;
        edd += d * d;
        extd[0] += d;
        for k in 1..=2 {
            extd[2 * k - 1] += d * (k as f64 * t).cos();
            extd[2 * k] += d * (k as f64 * t).sin();
        }
    }
    assert!((rr - err).abs() < 1e-12 && (rd - erd).abs() < 1e-12 && (dd - edd).abs() < 1e-12);
    for (a, b) in xtd.iter().zip(&extd) {
        assert!((a - b).abs() < 1e-12);
    }
    assert!(harmonic_gauss_newton(&theta, &tau, &x, &coef[..4]).is_err());
    assert!(harmonic_gauss_newton(&theta, &tau, &x, &coef[..1]).is_err());
    assert!(harmonic_gauss_newton(&theta, &tau[..3], &x, &coef).is_err());
}

#[test]
fn rss_matches_the_explicit_residual() {
    let theta: Vec<f64> = (0..45).map(|i| 0.21 * i as f64).collect();
    let y: Vec<f64> = theta.iter().map(|t| (t + 0.2).cos() + 0.1).collect();
    let coef = [0.1, 0.9, -0.2, 0.05, 0.01];
    let s = harmonic_series(&theta, &coef).unwrap();
    let e: f64 = y.iter().zip(&s).map(|(a, b)| (a - b) * (a - b)).sum();
    let got = harmonic_rss(&theta, &y, &coef).unwrap();
    assert!((got - e).abs() <= 1e-14 * e.max(1.0));
    assert!(harmonic_rss(&theta, &y[..4], &coef).is_err());
    assert!(harmonic_rss(&theta, &y, &coef[..2]).is_err());
}

#[test]
fn cholesky_reproduces_the_matrix_and_refuses_indefinite_ones() {
    let m = 11; // not a multiple of LANES
    let a: Vec<f64> = (0..m * m)
        .map(|i| ((i * 7 % 13) as f64 - 6.0) / 10.0)
        .collect();
    let mut g = vec![0.0; m * m];
    for i in 0..m {
        for j in 0..m {
            g[i * m + j] = (0..m).map(|k| a[k * m + i] * a[k * m + j]).sum::<f64>()
                + if i == j { 1.0 } else { 0.0 };
        }
    }
    let r = cholesky_upper(&g, m).unwrap();
    for i in 0..m {
        for j in 0..m {
            let e: f64 = (0..m).map(|k| r[k * m + i] * r[k * m + j]).sum();
            assert!((e - g[i * m + j]).abs() < 1e-12, "({i}, {j})");
            if j < i {
                assert_eq!(r[i * m + j], 0.0);
            }
        }
    }
    let mut bad = g.clone();
    bad[0] = -1.0;
    assert!(cholesky_upper(&bad, m).is_err());
    assert!(cholesky_upper(&g[..10], m).is_err());
}
