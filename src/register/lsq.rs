//! The `levenberg-marquardt` crate's problem for camera fits: residuals as a function of
//! offsets of the free parameters from a base camera (so that the solver's trust region is
//! not scaled by absolute UTM coordinates), the Jacobian by central differences with each
//! parameter's step ([`Param::step`]).

use levenberg_marquardt::LeastSquaresProblem;
use nalgebra::{DMatrix, DVector, Dyn, Owned};

use super::params::Param;

/// A camera fit's residuals as a function of the offsets of its free parameters.
pub(crate) trait OffsetProblem {
    /// The free parameters, in the order of the offsets.
    fn free(&self) -> &[Param];
    /// The current offsets.
    fn offsets(&self) -> &DVector<f64>;
    /// Sets the current offsets.
    fn set_offsets(&mut self, x: &DVector<f64>);
    /// The residuals at offsets `x`.
    fn residuals_at(&self, x: &DVector<f64>) -> DVector<f64>;
}

/// The Jacobian of `p`'s residuals at its current offsets by central differences; `None`
/// if an entry is not finite.
pub(crate) fn jacobian<P: OffsetProblem>(p: &P) -> Option<DMatrix<f64>> {
    let x = p.offsets();
    let r0 = p.residuals_at(x);
    let mut j = DMatrix::zeros(r0.len(), p.free().len());
    for (k, param) in p.free().iter().enumerate() {
        let h = param.step();
        let (mut lo, mut hi) = (x.clone(), x.clone());
        lo[k] -= h;
        hi[k] += h;
        let d = (p.residuals_at(&hi) - p.residuals_at(&lo)) / (2.0 * h);
        j.set_column(k, &d);
    }
    j.iter().all(|v| v.is_finite()).then_some(j)
}

/// An [`OffsetProblem`] as the solver's problem.
pub(crate) struct Lsq<P>(pub P);

impl<P: OffsetProblem> LeastSquaresProblem<f64, Dyn, Dyn> for Lsq<P> {
    type ResidualStorage = Owned<f64, Dyn>;
    type JacobianStorage = Owned<f64, Dyn, Dyn>;
    type ParameterStorage = Owned<f64, Dyn>;

    fn set_params(&mut self, x: &DVector<f64>) {
        self.0.set_offsets(x);
    }

    fn params(&self) -> DVector<f64> {
        self.0.offsets().clone()
    }

    fn residuals(&self) -> Option<DVector<f64>> {
        let r = self.0.residuals_at(self.0.offsets());
        r.iter().all(|v| v.is_finite()).then_some(r)
    }

    fn jacobian(&self) -> Option<DMatrix<f64>> {
        jacobian(&self.0)
    }
}
