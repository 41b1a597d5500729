//! Polynomial interpolation through a few samples at arbitrary instants.

/// The Lagrange basis polynomial of node `m` at `x`:
/// ℓ_m(x) = Π_{l≠m} (x − x_l)/(x_m − x_l). The nodes must be distinct.
pub fn lagrange_basis(nodes: &[f64], m: usize, x: f64) -> f64 {
    (0..nodes.len()).filter(|&l| l != m).map(|l| (x - nodes[l]) / (nodes[m] - nodes[l])).product()
}

/// The polynomial of degree < n through the n points (`nodes[k]`,
/// `values[k]`), at `x`: Σ ℓ_k(x)·v_k, with the first value taken out
/// first, v₀ + Σ ℓ_k(x)·(v_k − v₀) (the basis sums to 1), so that large
/// values with small differences between them (a carrier phase's ramp) keep
/// their digits. Exact for polynomials of degree < n.
pub fn lagrange(nodes: &[f64], values: &[f64], x: f64) -> f64 {
    let base = values[0];
    base + (0..nodes.len()).map(|k| lagrange_basis(nodes, k, x) * (values[k] - base)).sum::<f64>()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_cubic_through_four_points_is_exact() {
        let p = |x: f64| 1e6 + 3.0 * x - 0.5 * x * x + 0.25 * x * x * x;
        let nodes = [0.1, 0.35, 0.4, 1.0];
        let values = nodes.map(p);
        for x in [-0.2, 0.0, 0.37, 0.7, 1.3] {
            assert!((lagrange(&nodes, &values, x) - p(x)).abs() < 1e-8, "{x}");
        }
        assert_eq!(lagrange(&nodes, &values, nodes[2]), values[2]);
        // The basis sums to one and is 1 at its own node, 0 at the others.
        let sum: f64 = (0..4).map(|m| lagrange_basis(&nodes, m, 0.77)).sum();
        assert!((sum - 1.0).abs() < 1e-12);
        assert_eq!((lagrange_basis(&nodes, 1, nodes[1]), lagrange_basis(&nodes, 1, nodes[3])), (1.0, 0.0));
    }
}
