//! `POST /v1/scene`: the design values at each support (data collectors) — the request's
//! `design_percentile` and the `design_values` of each support entry of the statistics.

use serde::Serialize;
use utoipa::ToSchema;

use super::common::{Bound, Checker, FieldDefault, NumberField, number_schemas};
use super::migration::SummaryDto;
use crate::physics::scene::{DESIGN_PERCENTILE, DesignValue, DesignValues};

/// `design_percentile` of a scene: the percentile of the design values at each support.
pub const DESIGN_PERCENTILE_FIELD: NumberField = NumberField {
    description: "Percentile p of the design values at each support (statistics.supports[].\n\
                  design_values), in [0.5, 0.999]: the type-7 p-quantile over the runs that\n\
                  reached the support, with its distribution-free 95 % interval.",
    default: FieldDefault::Value(DESIGN_PERCENTILE),
    lo: Bound::Closed(0.5),
    hi: Bound::Closed(0.999),
    unit: "",
    example: 0.95,
    nullable: false,
};

number_schemas! { design_percentile_schema => DESIGN_PERCENTILE_FIELD; }

/// Checks the request's `design_percentile` against its documented interval.
pub fn check_design_percentile(ck: &mut Checker, v: f64) -> bool {
    DESIGN_PERCENTILE_FIELD.check(ck, "/design_percentile", v)
}

/// One quantity at a support over the runs that reached it, in the unit its field names.
#[derive(Debug, Clone, PartialEq, Serialize, ToSchema)]
pub struct DesignValueDto {
    /// Number of runs that reached the support.
    pub count: u64,
    /// Summary (mean, percentiles, max, histogram) over those runs.
    pub summary: SummaryDto,
    /// The value at `design_percentile` (Hyndman–Fan type 7, as the summary's percentiles).
    pub design_value: f64,
    /// Distribution-free 95 % confidence interval [lower, upper] of that percentile: the order
    /// statistics X₍ₗ₎ and X₍ᵤ₎ with equal binomial tails (l the largest rank with
    /// P(B ≤ l − 1) ≤ 2.5 %, u the smallest with P(B ≤ u − 1) ≥ 97.5 %, B ~ Binomial(count, p));
    /// a bound is null when too few runs reached the support for it (the upper one needs
    /// pⁿ ≤ 2.5 %: 72 runs at p = 0.95).
    pub design_ci95: [Option<f64>; 2],
}

impl From<&DesignValue> for DesignValueDto {
    fn from(d: &DesignValue) -> Self {
        Self {
            count: d.summary.count,
            summary: (&d.summary).into(),
            design_value: d.value,
            design_ci95: d.ci95,
        }
    }
}

/// The state of the rock on reaching a support, over the runs of the ensemble that reached it
/// (within the contact capacity or not): what a guard or a column at that support must take.
#[derive(Debug, Clone, PartialEq, Serialize, ToSchema)]
pub struct DesignValuesDto {
    /// The percentile p of `design_value` (the request's `design_percentile`).
    pub design_percentile: f64,
    /// Impact speed towards the support (as `impact_velocity_m_s`), m/s.
    pub impact_speed_m_s: DesignValueDto,
    /// Kinetic energy on reaching, translation + rotation, J.
    pub kinetic_energy_j: DesignValueDto,
    /// Translational kinetic energy ½ m v² on reaching, J.
    pub translational_energy_j: DesignValueDto,
    /// Rotational kinetic energy on reaching, J: the rigid block's ½ ωᵀIω; the lumped mass's
    /// rolling sphere ½ (2/5 m r²) ω² = m v²/5 (and the spin it keeps in flight), 0 sliding.
    pub rotational_energy_j: DesignValueDto,
    /// Height of the rock's lowest point above the floor (along its normal) where it reached the
    /// support's line, m (≥ 0; the lumped mass's point: 0 on the ground, its flight height in
    /// the air): the height a guard must exceed.
    pub passing_height_m: DesignValueDto,
}

impl From<&DesignValues> for DesignValuesDto {
    fn from(d: &DesignValues) -> Self {
        Self {
            design_percentile: d.percentile,
            impact_speed_m_s: (&d.impact_speed).into(),
            kinetic_energy_j: (&d.kinetic_energy).into(),
            translational_energy_j: (&d.translational_energy).into(),
            rotational_energy_j: (&d.rotational_energy).into(),
            passing_height_m: (&d.passing_height).into(),
        }
    }
}
