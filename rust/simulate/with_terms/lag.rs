//! Weights of the sensor lag's exponential step (module header of `with_terms.rs`).

/// Below this `r = h/tau` the `phi` functions of the lag are summed as Taylor series (the closed
/// forms cancel there); [`PHI_TERMS`] terms make the truncation below `1/23! < 1e-22`.
const PHI_SERIES_BELOW: f64 = 1.0;
const PHI_TERMS: usize = 20;

/// Weights of the exponential lag step (module header): `(e^-r, r c_0, r c_m, r c_1)`.
pub(super) fn lag_weights(r: f64) -> (f64, f64, f64, f64) {
    if !r.is_finite() {
        // tau so small that h/tau overflows: the sensor follows F at once.
        return (0.0, 0.0, 0.0, 1.0);
    }
    let z = -r;
    let (p1, p2, p3) = if r < PHI_SERIES_BELOW {
        // phi_k(z) = sum_j z^j / (j + k)!, summed from the smallest term.
        let mut fact = [1.0f64; PHI_TERMS + 4];
        for i in 1..fact.len() {
            fact[i] = fact[i - 1] * i as f64;
        }
        let phi = |k: usize| {
            let mut acc = 0.0;
            for j in (0..PHI_TERMS).rev() {
                acc = acc * z + 1.0 / fact[j + k];
            }
            acc
        };
        (phi(1), phi(2), phi(3))
    } else {
        let p1 = z.exp_m1() / z;
        let p2 = (p1 - 1.0) / z;
        let p3 = (p2 - 0.5) / z;
        (p1, p2, p3)
    };
    (
        z.exp(),
        r * (p1 - 3.0 * p2 + 4.0 * p3),
        r * (4.0 * p2 - 8.0 * p3),
        r * (4.0 * p3 - p2),
    )
}
