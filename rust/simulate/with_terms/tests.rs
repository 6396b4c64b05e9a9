//! Tests of the simulation with terms.

use super::super::on_x::OnXValues;
use super::super::Source;
use super::derivatives::Derivatives;
use super::lag::lag_weights;
use super::*;
use crate::terms::{TermKind, COULOMB_SMOOTHING_KEY};
use approx::assert_relative_eq;

fn sine(amplitude: f64, omega: f64) -> Input<'static> {
    Input::Sine { amplitude, omega }
}

fn plant() -> (TransferFunction, BoucWen) {
    (
        TransferFunction::new(&[1.0], &[0.2, 1.0], 0.05).unwrap(),
        BoucWen::new(1.0, 1.0, 0.5, 1.5, 0.0).unwrap(),
    )
}

#[test]
fn without_dynamic_terms_x_and_w_are_the_plain_ones() {
    let (tf, bw) = plant();
    let terms = TermValues {
        offset: 0.3,
        stiffness: 0.5,
        viscous: 0.1,
        inertia: 0.01,
        coulomb: 0.2,
        ..TermValues::default()
    };
    let (u, om, dt) = (1.3, 2.0, 0.02);
    let a = simulate(&tf, &bw, sine(u, om), dt, 400, 3).unwrap();
    let b = simulate_with_terms(&tf, &bw, &terms, sine(u, om), dt, 400, 3).unwrap();
    assert_eq!((a.x, a.w.clone()), (b.x, b.w));
    for k in 0..400 {
        let t = k as f64 * dt;
        let (c, s) = ((om * t).cos(), (om * t).sin());
        let extra = 0.5 * u * c - 0.1 * u * om * s - 0.01 * u * om * om * c
            + 0.2 * (-u * om * s / (0.01 * u * om)).tanh();
        assert_relative_eq!(b.y[k], 0.3 + a.w[k] + extra, epsilon = 1e-13);
    }
}

#[test]
fn terms_on_x_follow_the_linear_part_and_leave_x_and_w_alone() {
    // A resonant G with a delay: after the transient, the terms on x are
    // Re[(k + c j w - m w^2) G(j w) U e^{j w t}] and friction follows sgn(xdot).
    let tf = TransferFunction::new(&[1.0], &[0.05, 0.1, 1.0], 0.073).unwrap();
    let bw = BoucWen::new(1.0, 1.0, 0.5, 1.5, 0.0).unwrap();
    let on_x = OnXValues {
        stiffness: 0.4,
        viscous: 0.05,
        inertia: 0.01,
        ..OnXValues::default()
    };
    let terms = TermValues {
        on_x,
        offset: 0.1,
        ..TermValues::default()
    };
    let (u, om, dt, n) = (1.3, 3.0, 0.01, 4000);
    let a = simulate(&tf, &bw, sine(u, om), dt, n, 3).unwrap();
    let b = simulate_with_terms(&tf, &bw, &terms, sine(u, om), dt, n, 3).unwrap();
    assert_eq!((&a.x, &a.w), (&b.x, &b.w));
    let (re, im) = tf.freq_response(om);
    let g = nalgebra::Complex::new(re, im);
    let factor = nalgebra::Complex::new(0.4 - 0.01 * om * om, 0.05 * om);
    for k in 3000..n {
        let t = k as f64 * dt;
        let e = nalgebra::Complex::from_polar(u, om * t);
        assert_relative_eq!(b.y[k] - 0.1 - b.w[k], (factor * g * e).re, epsilon = 1e-7);
        // x itself is the plain one: k x is its share.
    }
    // The augmented integrator (forced by a vanishing lag: ys = F) computes the same terms
    // from its own state, to rounding (the delay is off the grid: at t = delay the input
    // steps from 0 to U and xddot with it, and the two paths' stage times round apart).
    let lagged = TermValues {
        sensor_lag: 1e-300,
        ..terms
    };
    let c = simulate_with_terms(&tf, &bw, &lagged, sine(u, om), dt, n, 3).unwrap();
    for k in 1..n {
        assert_relative_eq!(c.y[k], b.y[k], epsilon = 1e-12);
    }
    // Friction on x: +f where xdot > 0 well beyond eps |A| omega, -f where below.
    let fric = TermValues {
        on_x: OnXValues {
            coulomb: 0.3,
            coulomb_smoothing: 0.02,
            ..OnXValues::default()
        },
        ..TermValues::default()
    };
    let f = simulate_with_terms(&tf, &bw, &fric, sine(u, om), dt, n, 3).unwrap();
    let peak = u * g.norm() * om;
    for k in 3000..n {
        let t = k as f64 * dt;
        let xdot =
            (nalgebra::Complex::new(0.0, om) * g * nalgebra::Complex::from_polar(u, om * t)).re;
        if xdot.abs() > 0.2 * peak {
            assert_relative_eq!(f.y[k] - f.w[k], 0.3 * xdot.signum(), epsilon = 1e-6);
        }
    }
}

#[test]
fn a_blow_up_with_terms_names_the_terms_not_the_data() {
    let (tf, bw) = plant();
    let terms = TermValues {
        degradation: 1e300,
        ..TermValues::default()
    };
    let e = simulate_with_terms(&tf, &bw, &terms, sine(1.0, 2.0), 0.05, 400, 2).unwrap_err();
    assert!(matches!(e, CoreError::NonFinite(_)), "{e}");
    let msg = e.to_string();
    assert!(
        msg.contains("blew up") && msg.contains("degradation = 1e300"),
        "{msg}"
    );
    // A term that overflows y alone (no state): blamed too.
    let terms = TermValues {
        on_x: OnXValues {
            inertia: 1e308,
            ..OnXValues::default()
        },
        ..TermValues::default()
    };
    let e = simulate_with_terms(&tf, &bw, &terms, sine(1.0, 30.0), 0.005, 400, 2).unwrap_err();
    assert!(e.to_string().contains("inertia@x = 1e308"), "{e}");
}

#[test]
fn zero_dynamic_terms_reproduce_the_plain_path() {
    // delta = 0 and b = 0 on the augmented integrator: only rounding apart from simulate().
    let (tf, bw) = plant();
    let terms = TermValues {
        sensor_lag: 1e-300, // forces the augmented path; h/tau overflows -> ys = F
        ..TermValues::default()
    };
    let a = simulate(&tf, &bw, sine(1.0, 3.0), 0.01, 600, 2).unwrap();
    let b = simulate_with_terms(&tf, &bw, &terms, sine(1.0, 3.0), 0.01, 600, 2).unwrap();
    for k in 0..600 {
        assert_relative_eq!(a.x[k], b.x[k], epsilon = 1e-14);
        assert_relative_eq!(a.w[k], b.w[k], epsilon = 1e-13);
    }
    // with ys = F (after the first sample, where ys(0) = 0)
    for k in 1..600 {
        assert_relative_eq!(b.y[k], b.w[k], epsilon = 1e-13);
    }
}

#[test]
fn lag_weights_limits() {
    // r -> 0: Simpson's weights (1, 4, 1)/6 scaled by r.
    let r = 1e-6;
    let (e, c0, cm, c1) = lag_weights(r);
    assert_relative_eq!(e, (-r).exp(), max_relative = 1e-15);
    assert_relative_eq!(c0 / r, 1.0 / 6.0, max_relative = 1e-5);
    assert_relative_eq!(cm / r, 2.0 / 3.0, max_relative = 1e-5);
    assert_relative_eq!(c1 / r, 1.0 / 6.0, max_relative = 1e-5);
    // Exact for quadratic F, on both sides of the series switch. Constant F = 1:
    // ys+ = e ys + (1 - e). Linear F = s/h from ys(0) = 0: 1 - (1 - e^-r)/r. Quadratic
    // F = (s/h)^2: 1 - 2/r + 2 (1 - e^-r)/r^2.
    for r in [0.3, 0.999, 1.0, 2.5, 40.0] {
        let (e, c0, cm, c1) = lag_weights(r);
        assert_relative_eq!(c0 + cm + c1, 1.0 - e, max_relative = 1e-13);
        assert_relative_eq!(0.5 * cm + c1, 1.0 - (1.0 - e) / r, max_relative = 1e-13);
        let quad = 1.0 - 2.0 / r + 2.0 * (1.0 - e) / (r * r);
        assert_relative_eq!(0.25 * cm + c1, quad, max_relative = 1e-12);
    }
    assert_eq!(lag_weights(f64::INFINITY), (0.0, 0.0, 0.0, 1.0));
}

#[test]
fn hermite_second_derivative_and_peak_rate() {
    // A cubic on the interior is not reproduced by Catmull-Rom, but a quadratic is:
    // u = t^2 gives uddot = 2 in the interior intervals and max |udot| = 2 t at the end slope.
    let dt = 0.1;
    let u: Vec<f64> = (0..30).map(|k| (k as f64 * dt).powi(2)).collect();
    let src = Hermite::new(&u, dt);
    for k in 1..27 {
        for s in [0.0, 0.25, 0.5, 0.9] {
            assert_relative_eq!(src.second((k as f64 + s) * dt), 2.0, epsilon = 1e-9);
        }
    }
    assert_eq!(src.second(40.0), 0.0);
    // Largest slope: on the last interval, between the central slope 5.6 and the one-sided
    // end slope 5.7 the cubic's slope peaks at its vertex, 5.7 + 1/30 (by hand).
    assert_relative_eq!(src.peak_rate(), 5.7 + 1.0 / 30.0, max_relative = 1e-12);
    // A sine's peak comes from interior vertices: it bounds a dense scan of the interpolant's
    // slope and is attained by it, and it is U omega up to the Catmull-Rom slope error
    // (omega dt)^2/6 = 1.5e-4.
    let (amp, om, dt) = (2.0, 3.0, 0.01);
    let us: Vec<f64> = (0..400).map(|k| amp * (om * k as f64 * dt).cos()).collect();
    let src = Hermite::new(&us, dt);
    let scan = (0..400_000)
        .map(|i| src.at(i as f64 * dt / 1000.0).1.abs())
        .fold(0.0, f64::max);
    assert!(
        src.peak_rate() >= scan * (1.0 - 1e-14),
        "{} < {scan}",
        src.peak_rate()
    );
    assert_relative_eq!(src.peak_rate(), scan, max_relative = 1e-7);
    assert_relative_eq!(src.peak_rate(), amp * om, max_relative = 2e-4);
    let s = Sine {
        amplitude: -amp,
        omega: om,
        neg_amplitude_omega: amp * om,
    };
    assert_eq!(s.peak_rate(), amp * om);
}

#[test]
fn asymmetry_saturates_at_the_two_levels() {
    // A large slow sine drives w to (beta + gamma +- delta)^(-1/mu) at the top and bottom.
    let tf = TransferFunction::new(&[1.0], &[1.0], 0.0).unwrap();
    let bw = BoucWen::new(1.0, 1.0, 0.5, 2.0, 0.0).unwrap();
    let terms = TermValues {
        asymmetry: 0.6,
        ..TermValues::default()
    };
    let (amp, om) = (30.0, 1.0);
    let n = 2000;
    let dt = 4.0 * std::f64::consts::PI / om / n as f64;
    let sim = simulate_with_terms(&tf, &bw, &terms, sine(amp, om), dt, n, 4).unwrap();
    let top = sim.w.iter().cloned().fold(f64::MIN, f64::max);
    let bottom = sim.w.iter().cloned().fold(f64::MAX, f64::min);
    assert_relative_eq!(top, (1.5f64 + 0.6).powf(-0.5), max_relative = 1e-6);
    assert_relative_eq!(bottom, -(1.5f64 - 0.6).powf(-0.5), max_relative = 1e-6);
}

#[test]
fn stiffness_degradation_keeps_the_level_and_pinching_slips_past_zero() {
    // A slow large sine through a static gain: eta leaves the saturation level, and pinching
    // takes (1 - zeta1) of the slope dw/dx at the band's centre on the loading branch.
    let tf = TransferFunction::new(&[1.0], &[1.0], 0.0).unwrap();
    let bw = BoucWen::new(1.0, 1.0, 0.5, 2.0, 0.0).unwrap();
    let (amp, om, n) = (30.0, 1.0, 4000);
    let dt = 4.0 * std::f64::consts::PI / om / n as f64;
    let run = |t: TermValues| simulate_with_terms(&tf, &bw, &t, sine(amp, om), dt, n, 4).unwrap();
    let d = TermValues::default();
    let soft = run(TermValues {
        stiffness_degradation: 0.05,
        ..d
    });
    let top = soft.w.iter().cloned().fold(f64::MIN, f64::max);
    assert_relative_eq!(top, 1.5f64.powf(-0.5), max_relative = 1e-4);
    let pinched = run(TermValues { pinching: 0.6, ..d });
    let plain = run(TermValues {
        sensor_lag: 1e-300,
        ..d
    });
    // Slope dw/dx where w crosses the band's centre going down (second half of the first period).
    let slope = |s: &TermSimulation, level: f64| {
        let k = (n / 2..n - 1)
            .find(|&k| s.w[k] >= level && s.w[k + 1] < level)
            .unwrap();
        (s.w[k + 1] - s.w[k]) / (s.x[k + 1] - s.x[k])
    };
    let centre = -PINCHING_CENTRE * 1.5f64.powf(-0.5);
    let ratio = slope(&pinched, centre) / slope(&plain, centre);
    assert!((ratio - 0.4).abs() < 0.02, "{ratio}");
}

#[test]
fn validation() {
    let (tf, bw) = plant();
    let bad = |t: TermValues, text: &str, nonfinite: bool| {
        let e = simulate_with_terms(&tf, &bw, &t, sine(1.0, 1.0), 0.1, 10, 1).unwrap_err();
        if nonfinite {
            assert!(matches!(e, CoreError::NonFinite(_)), "{e}");
        } else {
            assert!(matches!(e, CoreError::InvalidParameter(_)), "{e}");
        }
        assert!(e.to_string().contains(text), "{e}");
    };
    let d = TermValues::default();
    bad(
        TermValues {
            sensor_lag: -1.0,
            ..d
        },
        TermKind::SensorLag.name(),
        false,
    );
    bad(TermValues { play: -0.1, ..d }, TermKind::Play.name(), false);
    bad(
        TermValues {
            stiffness_degradation: -0.1,
            ..d
        },
        TermKind::StiffnessDegradation.name(),
        false,
    );
    bad(
        TermValues { pinching: 1.0, ..d },
        TermKind::Pinching.name(),
        false,
    );
    bad(
        TermValues {
            coulomb_smoothing: 0.0,
            ..d
        },
        COULOMB_SMOOTHING_KEY,
        false,
    );
    bad(
        TermValues {
            coulomb_smoothing: 0.6,
            ..d
        },
        COULOMB_SMOOTHING_KEY,
        false,
    );
    bad(
        TermValues {
            asymmetry: -1.5,
            ..d
        },
        "beta + gamma",
        false,
    );
    bad(
        TermValues {
            viscous: f64::NAN,
            ..d
        },
        TermKind::Viscous.name(),
        true,
    );
    let (offset, play) = (TermKind::Offset.name(), TermKind::Play.name());
    let e = TermValues::from_named([(offset, 1.0), ("spring", 2.0)]).unwrap_err();
    assert!(e.to_string().contains("\"spring\""), "{e}");
    let e = TermValues::from_named([(TermKind::Distortion.name(), 0.1)]).unwrap_err();
    assert!(e.to_string().contains("no time-domain form"), "{e}");
    let t = TermValues::from_named([(play, 0.2), (COULOMB_SMOOTHING_KEY, 0.05)]).unwrap();
    assert_eq!((t.play, t.coulomb_smoothing, t.offset), (0.2, 0.05, 0.0));
}
