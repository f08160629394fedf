//! The `levenberg-marquardt` crate's problem for camera fits: residuals as a function of
//! offsets of the free parameters from a base camera (so that the solver's trust region is
//! not scaled by absolute UTM coordinates), the Jacobian by central differences with each
//! parameter's step ([`Param::step`]).

use levenberg_marquardt::LeastSquaresProblem;
use nalgebra::{DMatrix, DVector, Dyn, Owned};

use super::params::{CameraParams, Param};

/// `base` with the free parameters `free` moved by the offsets `x`.
pub(crate) fn params_at(base: &CameraParams, free: &[Param], x: &DVector<f64>) -> CameraParams {
    let mut p = *base;
    for (k, &param) in free.iter().enumerate() {
        p.set(param, base.get(param) + x[k]);
    }
    p
}

/// A camera fit's residuals as a function of the offsets of its free parameters.
pub(crate) trait Residuals {
    /// The free parameters, in the order of the offsets.
    fn free(&self) -> &[Param];
    /// The residuals at offsets `x`.
    fn residuals_at(&self, x: &DVector<f64>) -> DVector<f64>;
    /// Their Jacobian at `x`; `None` if an entry is not finite. Default: central
    /// differences over all residuals ([`jacobian`]).
    fn jacobian_at(&self, x: &DVector<f64>) -> Option<DMatrix<f64>>
    where
        Self: Sized,
    {
        jacobian(self, x)
    }
}

/// The Jacobian of `p`'s residuals at offsets `x` by central differences; `None` if an
/// entry is not finite.
pub(crate) fn jacobian<P: Residuals>(p: &P, x: &DVector<f64>) -> Option<DMatrix<f64>> {
    let mut j: Option<DMatrix<f64>> = None;
    for (k, param) in p.free().iter().enumerate() {
        let h = param.step();
        let (mut lo, mut hi) = (x.clone(), x.clone());
        lo[k] -= h;
        hi[k] += h;
        let d = (p.residuals_at(&hi) - p.residuals_at(&lo)) / (2.0 * h);
        j.get_or_insert_with(|| DMatrix::zeros(d.len(), p.free().len()))
            .set_column(k, &d);
    }
    let j = j.unwrap_or_else(|| DMatrix::zeros(p.residuals_at(x).len(), 0));
    j.iter().all(|v| v.is_finite()).then_some(j)
}

/// A [`Residuals`] problem at offsets `x`, as the solver's problem.
pub(crate) struct Lsq<P> {
    /// The residuals.
    pub problem: P,
    /// The current offsets.
    pub x: DVector<f64>,
}

impl<P: Residuals> LeastSquaresProblem<f64, Dyn, Dyn> for Lsq<P> {
    type ResidualStorage = Owned<f64, Dyn>;
    type JacobianStorage = Owned<f64, Dyn, Dyn>;
    type ParameterStorage = Owned<f64, Dyn>;

    fn set_params(&mut self, x: &DVector<f64>) {
        self.x.copy_from(x);
    }

    fn params(&self) -> DVector<f64> {
        self.x.clone()
    }

    fn residuals(&self) -> Option<DVector<f64>> {
        let r = self.problem.residuals_at(&self.x);
        r.iter().all(|v| v.is_finite()).then_some(r)
    }

    fn jacobian(&self) -> Option<DMatrix<f64>> {
        self.problem.jacobian_at(&self.x)
    }
}
