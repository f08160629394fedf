//! The Degener et al. (2003) per-triangle energy and its gradient.
//!
//! For the Jacobian J of the linear map from a 3D triangle (in its own orthonormal 2D
//! frame) to the plane, with singular values s1 >= s2 > 0:
//!
//! E = (s1/s2 + s2/s1) · (s1·s2 + 1/(s1·s2))^θ = (|J|²_F / det J) · (det J + 1/det J)^θ.
//!
//! The first factor measures angle distortion (2 for a similarity), the second area
//! distortion (2 when det J = 1). E = +∞ when det J <= 0 (a flipped or degenerate
//! triangle), which makes every flip a barrier for the relaxation.

use super::mesh::{area2_3d, cross3, dot3, len3, sub3};

/// Precomputed 3D shape of one triangle: its area and the 2D gradients (in the
/// triangle's own orthonormal frame) of its three barycentric hat functions.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct FaceGeom {
    /// 3D area in square metres.
    pub area: f64,
    /// Gradient of the hat function of corner k, in 1/metre.
    pub grad: [[f64; 2]; 3],
}

impl FaceGeom {
    /// Geometry of the 3D triangle (p0, p1, p2); its frame's orientation makes the
    /// corners counter-clockwise, so a positive-det map preserves the winding.
    pub fn new(p0: [f64; 3], p1: [f64; 3], p2: [f64; 3]) -> FaceGeom {
        let e1 = sub3(p1, p0);
        let e2 = sub3(p2, p0);
        let l1 = len3(e1);
        let area2 = area2_3d(p0, p1, p2);
        if !(l1 > 0.0) || !(area2 > 0.0) {
            return FaceGeom {
                area: 0.0,
                grad: [[0.0; 2]; 3],
            };
        }
        let x = [e1[0] / l1, e1[1] / l1, e1[2] / l1];
        let n = cross3(e1, e2);
        let nl = len3(n);
        let nn = [n[0] / nl, n[1] / nl, n[2] / nl];
        let y = cross3(nn, x);
        let q = [[0.0, 0.0], [l1, 0.0], [dot3(e2, x), dot3(e2, y)]];
        let mut grad = [[0.0; 2]; 3];
        for k in 0..3 {
            let a = q[(k + 1) % 3];
            let b = q[(k + 2) % 3];
            // perp(b - a) / (2A): rotates the opposite edge by +90 degrees (points inward).
            grad[k] = [-(b[1] - a[1]) / area2, (b[0] - a[0]) / area2];
        }
        FaceGeom {
            area: 0.5 * area2,
            grad,
        }
    }

    /// The Jacobian J[r][c] = Σ_k uv_k[r] · grad_k[c].
    pub fn jacobian(&self, uv: [[f64; 2]; 3]) -> [[f64; 2]; 2] {
        let mut j = [[0.0; 2]; 2];
        for k in 0..3 {
            for r in 0..2 {
                for c in 0..2 {
                    j[r][c] += uv[k][r] * self.grad[k][c];
                }
            }
        }
        j
    }
}

/// det J.
pub(crate) fn det2(j: &[[f64; 2]; 2]) -> f64 {
    j[0][0] * j[1][1] - j[0][1] * j[1][0]
}

/// Singular values (s1 >= s2 >= 0) of a 2x2 matrix.
pub(crate) fn singular_values(j: &[[f64; 2]; 2]) -> (f64, f64) {
    let (a, b, c, d) = (j[0][0], j[0][1], j[1][0], j[1][1]);
    let e = 0.5 * (a + d);
    let f = 0.5 * (a - d);
    let g = 0.5 * (c + b);
    let h = 0.5 * (c - b);
    let q = (e * e + h * h).sqrt();
    let r = (f * f + g * g).sqrt();
    (q + r, (q - r).abs())
}

/// p^θ, with a fast path for small integer θ (the common settings).
#[inline]
fn pow_theta(p: f64, theta: f64) -> f64 {
    if theta == 0.0 {
        1.0
    } else if theta == 1.0 {
        p
    } else if theta == 2.0 {
        p * p
    } else if theta == 3.0 {
        p * p * p
    } else {
        p.powf(theta)
    }
}

/// The Degener energy of one Jacobian for area/angle weight `theta`; +∞ if det <= 0.
pub(crate) fn energy(j: &[[f64; 2]; 2], theta: f64) -> f64 {
    let d = det2(j);
    if !(d > 0.0) {
        return f64::INFINITY;
    }
    let fro = j[0][0] * j[0][0] + j[0][1] * j[0][1] + j[1][0] * j[1][0] + j[1][1] * j[1][1];
    let p = d + 1.0 / d;
    (fro / d) * pow_theta(p, theta)
}

/// The energy and its derivative with respect to J (dE/dJ[r][c]); `None` if det <= 0.
/// (Reference for the tests of [`vertex_grad_hess`].)
#[cfg(test)]
pub(crate) fn energy_grad(j: &[[f64; 2]; 2], theta: f64) -> Option<(f64, [[f64; 2]; 2])> {
    let d = det2(j);
    if !(d > 0.0) {
        return None;
    }
    let fro = j[0][0] * j[0][0] + j[0][1] * j[0][1] + j[1][0] * j[1][0] + j[1][1] * j[1][1];
    let p = d + 1.0 / d;
    let pt = pow_theta(p, theta);
    let e = (fro / d) * pt;
    // d det / dJ (cofactor matrix).
    let cof = [[j[1][1], -j[1][0]], [-j[0][1], j[0][0]]];
    let a = pt / d; // coefficient of 2J
    let b = -fro / (d * d) * pt + (fro / d) * theta * pt / p * (1.0 - 1.0 / (d * d)); // coefficient of cof
    let mut g = [[0.0; 2]; 2];
    for r in 0..2 {
        for c in 0..2 {
            g[r][c] = a * 2.0 * j[r][c] + b * cof[r][c];
        }
    }
    Some((e, g))
}

/// Energy, gradient and Hessian with respect to the UV of corner `k` alone (the other
/// corners fixed); `None` if det <= 0. J is affine in that UV and det J is linear in it.
pub(crate) fn vertex_grad_hess(
    geom: &FaceGeom,
    j: &[[f64; 2]; 2],
    k: usize,
    theta: f64,
) -> Option<(f64, [f64; 2], [[f64; 2]; 2])> {
    let d = det2(j);
    if !(d > 0.0) {
        return None;
    }
    let g = geom.grad[k];
    let fro = j[0][0] * j[0][0] + j[0][1] * j[0][1] + j[1][0] * j[1][0] + j[1][1] * j[1][1];
    let p = d + 1.0 / d;
    let q = 1.0 - 1.0 / (d * d);
    let b = pow_theta(p, theta);
    let a = fro / d;
    let jg = [
        j[0][0] * g[0] + j[0][1] * g[1],
        j[1][0] * g[0] + j[1][1] * g[1],
    ];
    let cg = [
        j[1][1] * g[0] - j[1][0] * g[1],
        -j[0][1] * g[0] + j[0][0] * g[1],
    ];
    let gg = g[0] * g[0] + g[1] * g[1];
    // dA·g, dB·g (A = |J|²/det, B = P^θ).
    let da = [
        2.0 * jg[0] / d - fro / (d * d) * cg[0],
        2.0 * jg[1] / d - fro / (d * d) * cg[1],
    ];
    let beta = if theta == 0.0 { 0.0 } else { theta * b / p * q };
    let db = [beta * cg[0], beta * cg[1]];
    let gamma = if theta == 0.0 {
        0.0
    } else {
        theta * ((theta - 1.0) * b / (p * p) * q * q + 2.0 * b / p / (d * d * d))
    };
    let mut h = [[0.0; 2]; 2];
    for r in 0..2 {
        for s in 0..2 {
            let id = if r == s { 1.0 } else { 0.0 };
            let d2a = 2.0 * gg / d * id - 2.0 / (d * d) * (jg[r] * cg[s] + cg[r] * jg[s])
                + 2.0 * fro / (d * d * d) * cg[r] * cg[s];
            h[r][s] = b * d2a + da[r] * db[s] + db[r] * da[s] + a * gamma * cg[r] * cg[s];
        }
    }
    let grad = [b * da[0] + a * db[0], b * da[1] + a * db[1]];
    Some((a * b, grad, h))
}

/// Derivative of det J with respect to the UV of corner `k` (det J is linear in it).
pub(crate) fn det_slope(geom: &FaceGeom, j: &[[f64; 2]; 2], k: usize) -> [f64; 2] {
    let g = geom.grad[k];
    let cof = [[j[1][1], -j[1][0]], [-j[0][1], j[0][0]]];
    [
        cof[0][0] * g[0] + cof[0][1] * g[1],
        cof[1][0] * g[0] + cof[1][1] * g[1],
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn identity_map_has_minimal_energy() {
        let g = FaceGeom::new([0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.5, 1.5, 0.0]);
        let j = g.jacobian([[0.0, 0.0], [2.0, 0.0], [0.5, 1.5]]);
        assert!(
            (j[0][0] - 1.0).abs() < 1e-12 && j[0][1].abs() < 1e-12 && (j[1][1] - 1.0).abs() < 1e-12
        );
        for theta in [0.0, 1.0, 3.0] {
            let e = energy(&j, theta);
            assert!((e - 2.0 * 2f64.powf(theta)).abs() < 1e-9);
            let (_, gr) = energy_grad(&j, theta).unwrap();
            for r in gr {
                for c in r {
                    assert!(c.abs() < 1e-9, "gradient at the minimum: {gr:?}");
                }
            }
        }
    }

    #[test]
    fn gradient_matches_finite_differences() {
        let j = [[1.3, 0.4], [-0.2, 0.7]];
        for theta in [0.0, 0.5, 3.0] {
            let (_, g) = energy_grad(&j, theta).unwrap();
            for r in 0..2 {
                for c in 0..2 {
                    let h = 1e-6;
                    let mut jp = j;
                    jp[r][c] += h;
                    let mut jm = j;
                    jm[r][c] -= h;
                    let fd = (energy(&jp, theta) - energy(&jm, theta)) / (2.0 * h);
                    assert!(
                        (fd - g[r][c]).abs() < 1e-5 * (1.0 + fd.abs()),
                        "theta {theta} [{r}][{c}]: {fd} vs {}",
                        g[r][c]
                    );
                }
            }
        }
    }

    #[test]
    fn vertex_hessian_matches_finite_differences() {
        let geom = FaceGeom::new([0.0, 0.0, 0.0], [2.0, 0.1, 0.5], [0.3, 1.5, 2.0]);
        let uv = [[0.1, 0.2], [1.9, 0.4], [0.5, 2.2]];
        for theta in [0.0, 0.5, 1.0, 3.0] {
            for k in 0..3 {
                let at = |x: [f64; 2]| {
                    let mut u = uv;
                    u[k] = x;
                    vertex_grad_hess(&geom, &geom.jacobian(u), k, theta).unwrap()
                };
                let (e, g, h) = at(uv[k]);
                assert!((e - energy(&geom.jacobian(uv), theta)).abs() < 1e-12 * e);
                let eps = 1e-6;
                for s in 0..2 {
                    let mut xp = uv[k];
                    xp[s] += eps;
                    let mut xm = uv[k];
                    xm[s] -= eps;
                    let (ep, gp, _) = at(xp);
                    let (em, gm, _) = at(xm);
                    let fd = (ep - em) / (2.0 * eps);
                    assert!(
                        (fd - g[s]).abs() < 1e-5 * (1.0 + fd.abs()),
                        "theta {theta} k {k} grad {s}: {fd} vs {}",
                        g[s]
                    );
                    for r in 0..2 {
                        let fdh = (gp[r] - gm[r]) / (2.0 * eps);
                        assert!(
                            (fdh - h[r][s]).abs() < 1e-4 * (1.0 + fdh.abs()),
                            "theta {theta} k {k} H[{r}][{s}]: {fdh} vs {}",
                            h[r][s]
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn singular_values_of_known_matrix() {
        let (s1, s2) = singular_values(&[[3.0, 0.0], [0.0, -2.0]]);
        assert!((s1 - 3.0).abs() < 1e-12 && (s2 - 2.0).abs() < 1e-12);
        let c = 0.6f64;
        let s = 0.8f64;
        // rotation * diag(5, 0.5)
        let (s1, s2) = singular_values(&[[c * 5.0, -s * 0.5], [s * 5.0, c * 0.5]]);
        assert!((s1 - 5.0).abs() < 1e-12 && (s2 - 0.5).abs() < 1e-12);
    }

    #[test]
    fn flipped_is_infinite() {
        assert!(energy(&[[1.0, 0.0], [0.0, -1.0]], 3.0).is_infinite());
        assert!(energy_grad(&[[0.0, 0.0], [0.0, 0.0]], 3.0).is_none());
    }
}
