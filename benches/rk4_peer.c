/*
 * C peer of the RK4 step of rust/simulate.rs (docs/design.md section 1), for benches/bench_pipeline.py.
 *
 * The classical fourth-order Runge-Kutta step of the Wiener system u -> G(s) -> x -> Bouc-Wen (2a) of the
 * seed paper, written the way a C programmer would: controllable canonical realisation of G (order
 * n <= RK4_MAX_ORDER, n = 0 a static gain), the delayed sine input u = U cos(omega (t - tau)) evaluated at
 * the stage times (the two mid-step stages share one evaluation; gcc turns each cos/sin pair into one
 * sincos), and one pow() per stage for |w|^mu.  Compiled by the bench with gcc -O3 -march=native.
 *
 * Same arguments and outputs as bouc_wen_id._core.simulate_sine after the realisation: a[n], c[n], d are
 * the companion form (rust/linear.rs), x and w receive n_samples values each.
 */
#include <math.h>

#define RK4_MAX_ORDER 16

static inline double sgn(double v) { return v > 0.0 ? 1.0 : (v < 0.0 ? -1.0 : 0.0); }

/* xsdot into dxs, returns wdot. */
static inline double rhs(int n, const double *a, const double *c, double d, double alpha, double beta,
                         double gamma, double mu, const double *xs, double w, double v, double vdot,
                         double *dxs) {
    double xdot = 0.0;
    if (n > 0) {
        double acc = 0.0;
        for (int i = 0; i < n; i++) acc += a[i] * xs[i];
        dxs[0] = -acc + v;
        for (int i = 1; i < n; i++) dxs[i] = xs[i - 1];
        for (int i = 0; i < n; i++) xdot += c[i] * dxs[i];
    }
    xdot += d * vdot;
    double wmu = pow(fabs(w), mu);
    return alpha * xdot - beta * fabs(xdot) * sgn(w) * wmu - gamma * xdot * wmu;
}

static inline void input(double t, double delay, double amplitude, double omega, double *v, double *vdot) {
    double tau = t - delay;
    if (tau < 0.0) {
        *v = 0.0;
        *vdot = 0.0;
        return;
    }
    double arg = omega * tau;
    *v = amplitude * cos(arg);
    *vdot = -amplitude * omega * sin(arg);
}

/* Returns 0, or -1 when n exceeds RK4_MAX_ORDER. */
int rk4_simulate_sine(int n, const double *a, const double *c, double d, double delay, double alpha,
                      double beta, double gamma, double mu, double w0, double amplitude, double omega,
                      double dt, long n_samples, long substeps, double *x_out, double *w_out) {
    if (n < 0 || n > RK4_MAX_ORDER) return -1;
    double xs[RK4_MAX_ORDER] = {0}, k1[RK4_MAX_ORDER], k2[RK4_MAX_ORDER], k3[RK4_MAX_ORDER],
           k4[RK4_MAX_ORDER], tmp[RK4_MAX_ORDER];
    double w = w0;
    double h = dt / (double)substeps, half_h = 0.5 * h, h_sixth = h / 6.0;
    for (long k = 0; k < n_samples; k++) {
        double t = (double)k * dt, v, vd;
        input(t, delay, amplitude, omega, &v, &vd);
        double acc = 0.0;
        for (int i = 0; i < n; i++) acc += c[i] * xs[i];
        x_out[k] = acc + d * v;
        w_out[k] = w;
        if (k == n_samples - 1) break;
        for (long s = 0; s < substeps; s++) {
            double ts = t + (double)s * h, v1, vd1, vm, vdm, v4, vd4;
            input(ts, delay, amplitude, omega, &v1, &vd1);
            input(ts + half_h, delay, amplitude, omega, &vm, &vdm);
            input(ts + h, delay, amplitude, omega, &v4, &vd4);
            double kw1 = rhs(n, a, c, d, alpha, beta, gamma, mu, xs, w, v1, vd1, k1);
            for (int i = 0; i < n; i++) tmp[i] = xs[i] + half_h * k1[i];
            double kw2 = rhs(n, a, c, d, alpha, beta, gamma, mu, tmp, w + half_h * kw1, vm, vdm, k2);
            for (int i = 0; i < n; i++) tmp[i] = xs[i] + half_h * k2[i];
            double kw3 = rhs(n, a, c, d, alpha, beta, gamma, mu, tmp, w + half_h * kw2, vm, vdm, k3);
            for (int i = 0; i < n; i++) tmp[i] = xs[i] + h * k3[i];
            double kw4 = rhs(n, a, c, d, alpha, beta, gamma, mu, tmp, w + h * kw3, v4, vd4, k4);
            for (int i = 0; i < n; i++) xs[i] += h_sixth * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
            w += h_sixth * (kw1 + 2.0 * kw2 + 2.0 * kw3 + kw4);
        }
    }
    return 0;
}
