//! `/v1/column`: the column's vibration after an impact, decoupled or coupled.

use super::{Calculation, Report, Stage};
use crate::physics::column::{ColumnCase, ColumnDetail, ColumnResult, solve_column};
use crate::physics::{Control, PhysicsError};

/// The column calculation.
#[derive(Debug, Clone, Copy)]
pub struct Column;

impl Calculation for Column {
    type Case = ColumnCase;
    type Result = ColumnResult;
    type Error = PhysicsError;

    fn solve(case: &ColumnCase, control: &Control) -> Result<Report<ColumnResult>, PhysicsError> {
        Ok(report(solve_column(case, control)?))
    }
}

/// The report of a solved column: its plan and its warnings (taken out of the result).
#[must_use]
pub fn report(mut r: ColumnResult) -> Report<ColumnResult> {
    let coupled = matches!(r.detail, ColumnDetail::Coupled(_));
    let plan = vec![
        Stage::ran("impact", "rigid-column contact maxima and duration"),
        Stage::ran(
            "column",
            if coupled {
                "rock + contact + Galerkin modes, adaptive Dormand–Prince with event location"
            } else {
                "mode 1 free vibration from w_mid(0), closed form"
            },
        ),
        if r.history.is_some() {
            Stage::ran("history", "sampled as output asks")
        } else {
            Stage::skipped("history", "output is null")
        },
    ];
    Report {
        warnings: std::mem::take(&mut r.warnings),
        result: r,
        plan,
    }
}
