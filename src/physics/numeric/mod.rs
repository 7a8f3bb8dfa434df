//! Numerical building blocks shared by the solvers, one algorithm per file: double-double
//! arithmetic, root finding, series evaluation, quadrature, the Dormand–Prince integrator, the
//! φ-functions of exponential integrators, the lower Lambert W branch and complete elliptic
//! integrals. Nothing here knows about rocks or
//! columns.

pub mod double_double;
pub mod elliptic;
pub mod expo;
pub mod lambert;
pub mod ode;
pub mod polynomial;
pub mod quadrature;
pub mod roots;
pub mod series;
