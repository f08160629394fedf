//! The symmetric Dirichlet energy of one 2x2 Jacobian F, its gradient and its Hessian
//! projected to positive semi-definite, from the analytic eigensystem of isotropic 2D
//! energies (Smith, De Goes & Kim 2019, "Analytic eigensystems for isotropic distortion
//! energies").
//!
//! Ψ(F) = |F|²_F + |F⁻¹|²_F = σ1² + σ2² + σ1⁻² + σ2⁻² (4 at a rotation, +∞ if det F <= 0).
//! With the signed SVD F = U diag(σ1, σ2) Vᵀ (U, V rotations) and Ψi = ∂Ψ/∂σi = 2σi − 2σi⁻³,
//! the four eigenpairs of ∂²Ψ/∂F² are
//! - scaling: U diag(1,0) Vᵀ and U diag(0,1) Vᵀ, eigenvalues 2 + 6σ1⁻⁴ and 2 + 6σ2⁻⁴ (> 0);
//! - flip: U [[0,1],[1,0]] Vᵀ/√2, eigenvalue (Ψ1 − Ψ2)/(σ1 − σ2)
//!   = 2 + 2(σ1² + σ1σ2 + σ2²)/(σ1σ2)³ (> 0, written without the division);
//! - twist: U [[0,−1],[1,0]] Vᵀ/√2, eigenvalue (Ψ1 + Ψ2)/(σ1 + σ2)
//!   = 2 − 2(σ1² − σ1σ2 + σ2²)/(σ1σ2)³, the only one that can be negative; it is clamped
//!   at 0, which is exactly the projection of the Hessian onto the PSD cone.
//!
//! Matrices are flattened row-major: (F00, F01, F10, F11).

/// Ψ, ∂Ψ/∂F (row-major) and the PSD-projected ∂²Ψ/∂F² (4x4) of one Jacobian; `None` if
/// det F <= 0.
pub(crate) fn eval(f: &[[f64; 2]; 2]) -> Option<(f64, [f64; 4], [[f64; 4]; 4])> {
    let (u, s1, s2, v) = svd2(f)?;
    let energy = s1 * s1 + s2 * s2 + 1.0 / (s1 * s1) + 1.0 / (s2 * s2);
    let psi1 = 2.0 * s1 - 2.0 / (s1 * s1 * s1);
    let psi2 = 2.0 * s2 - 2.0 / (s2 * s2 * s2);
    // Q = U M Vᵀ for a 2x2 M, flattened.
    let uq = |m: [[f64; 2]; 2]| -> [f64; 4] {
        let mut q = [0.0; 4];
        for r in 0..2 {
            for c in 0..2 {
                let mut x = 0.0;
                for a in 0..2 {
                    for b in 0..2 {
                        x += u[r][a] * m[a][b] * v[c][b];
                    }
                }
                q[2 * r + c] = x;
            }
        }
        q
    };
    let grad = uq([[psi1, 0.0], [0.0, psi2]]);
    let p = s1 * s2;
    let p3 = p * p * p;
    let h = std::f64::consts::FRAC_1_SQRT_2;
    let pairs = [
        (
            2.0 + 6.0 / (s1 * s1 * s1 * s1),
            uq([[1.0, 0.0], [0.0, 0.0]]),
        ),
        (
            2.0 + 6.0 / (s2 * s2 * s2 * s2),
            uq([[0.0, 0.0], [0.0, 1.0]]),
        ),
        (
            2.0 + 2.0 * (s1 * s1 + s1 * s2 + s2 * s2) / p3,
            uq([[0.0, h], [h, 0.0]]),
        ),
        (
            (2.0 - 2.0 * (s1 * s1 - s1 * s2 + s2 * s2) / p3).max(0.0),
            uq([[0.0, -h], [h, 0.0]]),
        ),
    ];
    let mut hess = [[0.0; 4]; 4];
    for (lambda, q) in pairs {
        if lambda == 0.0 {
            continue;
        }
        for a in 0..4 {
            for b in 0..4 {
                hess[a][b] += lambda * q[a] * q[b];
            }
        }
    }
    Some((energy, grad, hess))
}

/// Ψ alone (cheaper, for line searches); +∞ if det F <= 0.
pub(crate) fn energy(f: &[[f64; 2]; 2]) -> f64 {
    let d = f[0][0] * f[1][1] - f[0][1] * f[1][0];
    if !(d > 0.0) {
        return f64::INFINITY;
    }
    let fro = f[0][0] * f[0][0] + f[0][1] * f[0][1] + f[1][0] * f[1][0] + f[1][1] * f[1][1];
    fro + fro / (d * d)
}

/// A signed SVD (U, σ1, σ2, V) of a 2x2 matrix, as [`svd2`] returns it.
pub(crate) type Svd2 = ([[f64; 2]; 2], f64, f64, [[f64; 2]; 2]);

/// Signed SVD of a 2x2 matrix with positive determinant: F = U diag(σ1, σ2) Vᵀ with U, V
/// rotations and σ1 >= σ2 > 0; `None` if det F <= 0 or not finite.
pub(crate) fn svd2(f: &[[f64; 2]; 2]) -> Option<Svd2> {
    let (a, b, c, d) = (f[0][0], f[0][1], f[1][0], f[1][1]);
    let e = 0.5 * (a + d);
    let ff = 0.5 * (a - d);
    let g = 0.5 * (c + b);
    let h = 0.5 * (c - b);
    let q = (e * e + h * h).sqrt();
    let r = (ff * ff + g * g).sqrt();
    let (s1, s2) = (q + r, q - r);
    if !(s2 > 0.0) || !s1.is_finite() {
        return None;
    }
    let a1 = g.atan2(ff);
    let a2 = h.atan2(e);
    let theta = 0.5 * (a2 - a1);
    let phi = 0.5 * (a2 + a1);
    let rot = |t: f64| [[t.cos(), -t.sin()], [t.sin(), t.cos()]];
    // F = R(φ) diag R(θ), so U = R(φ) and Vᵀ = R(θ), i.e. V = R(−θ).
    Some((rot(phi), s1, s2, rot(-theta)))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mat(x: [f64; 4]) -> [[f64; 2]; 2] {
        [[x[0], x[1]], [x[2], x[3]]]
    }

    #[test]
    fn svd_reconstructs() {
        for f in [
            [1.3, 0.4, -0.2, 0.7],
            [2.0, 0.0, 0.0, 0.5],
            [0.3, -1.1, 0.9, 0.2],
            [1.0, 0.0, 0.0, 1.0],
        ] {
            let (u, s1, s2, v) = svd2(&mat(f)).unwrap();
            assert!(s1 >= s2 && s2 > 0.0);
            for r in 0..2 {
                for c in 0..2 {
                    let x = u[r][0] * s1 * v[c][0] + u[r][1] * s2 * v[c][1];
                    assert!((x - f[2 * r + c]).abs() < 1e-12, "{f:?}");
                }
            }
        }
        assert!(svd2(&mat([0.0, 1.0, 1.0, 0.0])).is_none());
    }

    #[test]
    fn gradient_and_hessian_match_finite_differences_where_convex() {
        // det > ~1.3: every eigenvalue is positive, so the projection changes nothing.
        for f in [
            [1.9, 0.3, -0.4, 1.2],
            [2.5, 0.0, 0.1, 1.0],
            [1.2, -0.9, 0.8, 1.5],
        ] {
            let (e, g, hs) = eval(&mat(f)).unwrap();
            assert!((e - energy(&mat(f))).abs() < 1e-12);
            let step = 1e-5;
            for a in 0..4 {
                let mut fp = f;
                fp[a] += step;
                let mut fm = f;
                fm[a] -= step;
                let fd = (energy(&mat(fp)) - energy(&mat(fm))) / (2.0 * step);
                assert!((fd - g[a]).abs() < 1e-6, "grad {a}: {fd} vs {}", g[a]);
                let (_, gp, _) = eval(&mat(fp)).unwrap();
                let (_, gm, _) = eval(&mat(fm)).unwrap();
                for b in 0..4 {
                    let fdh = (gp[b] - gm[b]) / (2.0 * step);
                    assert!(
                        (fdh - hs[a][b]).abs() < 1e-5,
                        "hess {a}{b}: {fdh} vs {}",
                        hs[a][b]
                    );
                }
            }
        }
    }

    #[test]
    fn projected_hessian_is_psd_when_compressed() {
        // det < 1: the twist eigenvalue of the true Hessian is negative.
        let f = mat([0.5, 0.1, -0.05, 0.4]);
        let (_, _, h) = eval(&f).unwrap();
        // Check xᵀHx >= 0 on many directions.
        for k in 0..64 {
            let t = k as f64 * 0.37;
            let x = [t.sin(), (2.0 * t).cos(), (3.0 * t).sin(), (0.5 * t).cos()];
            let mut q = 0.0;
            for a in 0..4 {
                for b in 0..4 {
                    q += x[a] * h[a][b] * x[b];
                }
            }
            assert!(q >= -1e-9, "{q}");
        }
        // The identity is the minimum: zero gradient.
        let (e, g, _) = eval(&mat([1.0, 0.0, 0.0, 1.0])).unwrap();
        assert!((e - 4.0).abs() < 1e-12 && g.iter().all(|x| x.abs() < 1e-12));
    }
}
