//! Gauss-Legendre quadrature on [-1, 1], the rule every integral of this floor is taken with
//! (the Fresnel moments, single scattering, the beam tables, the directional dipole's tests).
//! A leaf: it imports nothing of the crate.

use std::f64::consts::PI;

/// Nodes and weights of `n`-point Gauss-Legendre quadrature on [-1, 1] (Newton's method on the
/// Legendre polynomial from the Chebyshev-like initial guess).
pub fn gauss_legendre(n: usize) -> (Vec<f64>, Vec<f64>) {
    let mut nodes = vec![0.0; n];
    let mut weights = vec![0.0; n];
    for i in 0..n {
        let mut x = (PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        let mut dp = 1.0;
        for _ in 0..100 {
            let (mut p0, mut p1) = (1.0, x);
            for k in 2..=n {
                let k = k as f64;
                let p2 = ((2.0 * k - 1.0) * x * p1 - (k - 1.0) * p0) / k;
                p0 = p1;
                p1 = p2;
            }
            dp = n as f64 * (x * p1 - p0) / (x * x - 1.0);
            let step = p1 / dp;
            x -= step;
            if step.abs() < 1e-16 {
                break;
            }
        }
        nodes[i] = x;
        weights[i] = 2.0 / ((1.0 - x * x) * dp * dp);
    }
    (nodes, weights)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_rule_integrates_polynomials_of_degree_2n_minus_1_exactly() {
        for n in [1, 2, 5, 16] {
            let (x, w) = gauss_legendre(n);
            assert!((w.iter().sum::<f64>() - 2.0).abs() < 1e-13, "n {n}");
            // integral_-1^1 x^k dx = 2 / (k + 1) for even k, 0 for odd.
            for k in 0..2 * n as i32 {
                let exact = if k % 2 == 0 { 2.0 / f64::from(k + 1) } else { 0.0 };
                let got: f64 = x.iter().zip(&w).map(|(x, w)| w * x.powi(k)).sum();
                assert!((got - exact).abs() < 1e-12, "n {n} k {k}: {got} vs {exact}");
            }
        }
    }
}
