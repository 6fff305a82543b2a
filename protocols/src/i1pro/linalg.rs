//! The little dense linear algebra the inverse pipeline needs (the codec crate carries no
//! matrix library).

/// Solves `A·x = b` for a square `A` (row-major, `n × n`) by Gaussian elimination with
/// partial pivoting; `None` when `A` is singular to working precision.
pub fn solve(mut a: Vec<Vec<f64>>, mut b: Vec<f64>) -> Option<Vec<f64>> {
    let n = b.len();
    let scale = a
        .iter()
        .flat_map(|r| r.iter())
        .fold(0.0f64, |m, v| m.max(v.abs()));
    if scale == 0.0 || !scale.is_finite() {
        return None;
    }
    for col in 0..n {
        let pivot = (col..n).max_by(|&i, &j| a[i][col].abs().total_cmp(&a[j][col].abs()))?;
        if a[pivot][col].abs() <= scale * 1e-12 {
            return None;
        }
        a.swap(col, pivot);
        b.swap(col, pivot);
        for row in col + 1..n {
            let f = a[row][col] / a[col][col];
            if f != 0.0 {
                let (upper, lower) = a.split_at_mut(row);
                for (x, p) in lower[0][col..].iter_mut().zip(&upper[col][col..]) {
                    *x -= f * p;
                }
                b[row] -= f * b[col];
            }
        }
    }
    let mut x = vec![0.0; n];
    for row in (0..n).rev() {
        let s: f64 = (row + 1..n).map(|k| a[row][k] * x[k]).sum();
        x[row] = (b[row] - s) / a[row][row];
    }
    Some(x)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn solves_a_3x3_system_by_hand() {
        // 2x + y = 5, x + 3y + z = 9.75, y + 4z = 11 → x = 1.5, y = 2, z = 2.25 (by hand:
        // y = 5 − 2x, z = (11 − y)/4 = 1.5 + x/2, middle row: 16.5 − 4.5x = 9.75).
        let a = vec![
            vec![2.0, 1.0, 0.0],
            vec![1.0, 3.0, 1.0],
            vec![0.0, 1.0, 4.0],
        ];
        let x = solve(a, vec![5.0, 9.75, 11.0]).unwrap();
        let want = [1.5, 2.0, 2.25];
        for (g, w) in x.iter().zip(want) {
            assert!((g - w).abs() < 1e-12, "{x:?}");
        }
    }

    #[test]
    fn needs_pivoting_and_spots_singular_matrices() {
        // The zero in the corner forces a row swap: y = 1, x = 2.
        let x = solve(vec![vec![0.0, 1.0], vec![1.0, 0.0]], vec![1.0, 2.0]).unwrap();
        assert_eq!(x, vec![2.0, 1.0]);
        assert!(solve(vec![vec![1.0, 2.0], vec![2.0, 4.0]], vec![1.0, 2.0]).is_none());
        assert!(solve(vec![vec![0.0]], vec![1.0]).is_none());
    }
}
