//! The play (backlash) on the measured output, `play@output`: the measured output follows the
//! model's output `F` (after the sensor lag and the offset) through a dead band of half-width `c`,
//! `y = Play_c[F]`, in its periodic steady state on the averaged period's grid.
//!
//! Past the period's largest sample `F_max` the output is `F_max - c` and holds until `F` has come
//! down by `2 c`, then follows `F + c` down to the smallest sample, holds for `2 c` of rise and
//! follows `F - c` up again. Each sample's output is `F` at one sample (its own, or the reversal's
//! while it dwells) plus `s c`, `s = -1` after a rise and `+1` after a fall; so every parameter's
//! column is that sample's column, and `dy/dc = s`. When the period's range is at most `2 c` the
//! output never leaves the dead band: the mid-range, which no sample can move (`dy/dc = 0`).
//! The NumPy oracle is `reference/augmented.py`'s `output_play`.

/// Applies the play of half-width `c` to the work space `cols` (F, then the shared columns, then
/// g and phi, each of P samples) in place; `c_col` is the play's own column (its parameter is
/// `shared[c_col - 1]`), which becomes `dy/dc`.
pub(super) fn output_play(cols: &mut [Vec<f64>], c: f64, c_col: usize) {
    let f = &cols[0];
    let p = f.len();
    if p == 0 {
        return;
    }
    let (mut j_max, mut j_min) = (0, 0);
    for (j, &v) in f.iter().enumerate() {
        if v > f[j_max] {
            j_max = j;
        }
        if v < f[j_min] {
            j_min = j;
        }
    }
    // (source sample, sign of c) of every sample's output.
    let mut src = vec![(j_max, -1.0); p];
    if f[j_max] - f[j_min] <= 2.0 * c {
        let mid = 0.5 * (f[j_max] + f[j_min]);
        for (k, col) in cols.iter_mut().enumerate() {
            let v = if k == 0 {
                mid
            } else if k == c_col {
                0.0
            } else {
                0.5 * (col[j_max] + col[j_min])
            };
            col.iter_mut().for_each(|x| *x = v);
        }
        return;
    }
    let mut state = (f[j_max] - c, j_max, -1.0);
    for i in 1..=p {
        let j = (j_max + i) % p;
        if state.0 < f[j] - c {
            state = (f[j] - c, j, -1.0);
        } else if state.0 > f[j] + c {
            state = (f[j] + c, j, 1.0);
        }
        src[j] = (state.1, state.2);
    }
    for (k, col) in cols.iter_mut().enumerate() {
        let old = col.clone();
        for (v, &(s, sign)) in col.iter_mut().zip(&src) {
            *v = if k == c_col {
                sign
            } else if k == 0 {
                old[s] + sign * c
            } else {
                old[s]
            };
        }
    }
}

#[cfg(test)]
mod tests {
    use super::output_play;

    /// The steady play of a sampled cosine: two periods of the plain operator from rest, the second
    /// kept, against the periodic construction; `dy/dc` and a column moved with their sources.
    #[test]
    fn periodic_play_matches_two_periods_of_the_operator() {
        let p = 40;
        let c = 0.3;
        let f: Vec<f64> = (0..p)
            .map(|j| (2.0 * std::f64::consts::PI * j as f64 / p as f64 + 0.4).cos())
            .collect();
        let col: Vec<f64> = (0..p).map(|j| j as f64).collect();
        let mut cols = vec![f.clone(), col, vec![0.0; p]];
        output_play(&mut cols, c, 2);
        let mut state = 0.0f64.clamp(f[0] - c, f[0] + c);
        for k in 0..2 * p {
            state = state.clamp(f[k % p] - c, f[k % p] + c);
            if k >= p {
                assert!((cols[0][k - p] - state).abs() < 1e-15, "sample {}", k - p);
            }
        }
        for j in 0..p {
            let s = cols[1][j] as usize;
            assert!((cols[0][j] - (f[s] + cols[2][j] * c)).abs() < 1e-15);
            assert!(cols[2][j] == 1.0 || cols[2][j] == -1.0);
        }
        // A dead band wider than the range: the mid-range, which no parameter moves.
        let mut flat = vec![f.clone(), vec![1.0; p], vec![0.0; p]];
        output_play(&mut flat, 1.5, 2);
        assert!(flat[0].iter().all(|v| v.abs() < 1e-12) && flat[2].iter().all(|v| *v == 0.0));
    }
}
