//! Per-cell maps of an ensemble: the request object `output.maps` of `/v1/migration`
//! (`migration_output.maps` of `/v1/scene`), its checks and limits, and the `maps` answer.

use serde::{Deserialize, Serialize};
use serde_json::json;
use utoipa::ToSchema;

use super::common::Bound::Closed;
use super::common::{Checker, FieldDefault, NumberField, number_schemas};
use super::param::Layout;
use crate::config::Config;
use crate::physics::migration::maps::{BYTES_PER_PASSAGE, MapGrid, Maps};

/// Default number of cells along the dip.
pub const CELLS_ALONG_DIP: u32 = 60;
/// Default number of cells across.
pub const CELLS_ACROSS: u32 = 40;
/// Most cells along either axis.
pub const MAX_CELLS_PER_AXIS: u32 = 2000;

/// `output.maps.along_dip_min_m`.
pub const MAP_ALONG_DIP_MIN: NumberField = NumberField {
    description: "Upper edge of the map's first row of cells, m along the dip (the frame of \
                  release.along_dip_m), in [−10000, 10000] (default 0, the face's upper end).",
    default: FieldDefault::Value(0.0),
    lo: Closed(-10000.0),
    hi: Closed(10000.0),
    unit: "m",
    example: 0.0,
    nullable: false,
};

/// `output.maps.along_dip_max_m` (derived default: `face.length_m`; above `along_dip_min_m`).
pub const MAP_ALONG_DIP_MAX: NumberField = NumberField {
    description: "Lower edge of the map's last row of cells, m along the dip, in [−10000, 10000] \
                  and above along_dip_min_m (default face.length_m, the lower end).",
    default: FieldDefault::Derived,
    lo: Closed(-10000.0),
    hi: Closed(10000.0),
    unit: "m",
    example: 120.0,
    nullable: false,
};

/// `output.maps.across_min_m`.
pub const MAP_ACROSS_MIN: NumberField = NumberField {
    description: "First edge of the map across the face, m (y, the frame of release.across_m), in \
                  [−1000, 1000] (default −5).",
    default: FieldDefault::Value(-5.0),
    lo: Closed(-1000.0),
    hi: Closed(1000.0),
    unit: "m",
    example: -5.0,
    nullable: false,
};

/// `output.maps.across_max_m` (above `across_min_m`).
pub const MAP_ACROSS_MAX: NumberField = NumberField {
    description: "Last edge of the map across the face, m, in [−1000, 1000] and above \
                  across_min_m (default 5).",
    default: FieldDefault::Value(5.0),
    lo: Closed(-1000.0),
    hi: Closed(1000.0),
    unit: "m",
    example: 5.0,
    nullable: false,
};

number_schemas! {
    map_along_dip_min_schema => MAP_ALONG_DIP_MIN;
    map_along_dip_max_schema => MAP_ALONG_DIP_MAX;
    map_across_min_schema => MAP_ACROSS_MIN;
    map_across_max_schema => MAP_ACROSS_MAX;
}

/// The fields of `output.maps` with a documented default or bound, by JSON Pointer below the
/// output object.
pub const MAP_FIELDS: &[(&str, NumberField)] = &[
    ("along_dip_min_m", MAP_ALONG_DIP_MIN),
    ("along_dip_max_m", MAP_ALONG_DIP_MAX),
    ("across_min_m", MAP_ACROSS_MIN),
    ("across_max_m", MAP_ACROSS_MAX),
];

/// Per-cell maps of a Monte Carlo ensemble (RAMMS-style), on a grid of equal rectangular cells
/// in the face's frame: along the dip (m, from the upper end in the face's mean plane, as
/// `release.along_dip_m` and the supports) × across (y, m, as `release.across_m`). The floor
/// view draws cell (s, y) where it draws that face point: on the plane x = s cos θ; on a grid or
/// contour floor x = x₀ + s cos θ in the file's horizontal frame (x₀ the floor's upper edge),
/// turned into map E/N with `face.floor.map`. Each run's path is its centre projected on the
/// face (the foot of the perpendicular on the mean plane, and y), sampled at most half the
/// smaller cell side apart on every closed-form piece and at every rigid-block step, the chords
/// between samples walked cell by cell. Refused (422 naming `…/maps`) when cells × runs passes
/// the server's `max_map_cell_runs` or the cells pass `max_map_cells`, and in a sharded scene.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields, default)]
pub struct MapsDto {
    /// Number of cells along the dip, in [1, 2000].
    #[schema(default = 60, minimum = 1, maximum = 2000, example = 60)]
    pub cells_along_dip: u32,
    /// Number of cells across, in [1, 2000].
    #[schema(default = 40, minimum = 1, maximum = 2000, example = 40)]
    pub cells_across: u32,
    /// Upper edge of the first row of cells, m along the dip.
    #[schema(schema_with = map_along_dip_min_schema)]
    pub along_dip_min_m: f64,
    /// Lower edge of the last row of cells, m along the dip (default `face.length_m`).
    #[schema(schema_with = map_along_dip_max_schema)]
    #[serde(
        skip_serializing_if = "Option::is_none",
        default,
        deserialize_with = "super::common::non_null"
    )]
    pub along_dip_max_m: Option<f64>,
    /// First edge across, m.
    #[schema(schema_with = map_across_min_schema)]
    pub across_min_m: f64,
    /// Last edge across, m.
    #[schema(schema_with = map_across_max_schema)]
    pub across_max_m: f64,
}

impl Default for MapsDto {
    fn default() -> Self {
        Self {
            cells_along_dip: CELLS_ALONG_DIP,
            cells_across: CELLS_ACROSS,
            along_dip_min_m: MAP_ALONG_DIP_MIN.value(),
            along_dip_max_m: None,
            across_min_m: MAP_ACROSS_MIN.value(),
            across_max_m: MAP_ACROSS_MAX.value(),
        }
    }
}

impl MapsDto {
    /// Checks the grid and its size against the limits (`runs`: the ensemble's, None without
    /// one); fills the derived `along_dip_max_m` with `length` (m). `layout` names the output
    /// object. The grid when every check passed.
    pub fn resolve(
        &mut self,
        config: &Config,
        layout: Layout,
        length: f64,
        runs: Option<u64>,
        ck: &mut Checker,
    ) -> Option<MapGrid> {
        let p = |f: &str| format!("{}/{f}", layout.migration_output("maps"));
        let mut ok = ck.count(
            &p("cells_along_dip"),
            u64::from(self.cells_along_dip),
            1,
            u64::from(MAX_CELLS_PER_AXIS),
            "cells",
        );
        ok &= ck.count(
            &p("cells_across"),
            u64::from(self.cells_across),
            1,
            u64::from(MAX_CELLS_PER_AXIS),
            "cells",
        );
        let s1 = *self.along_dip_max_m.get_or_insert(length);
        ok &= MAP_ALONG_DIP_MIN.check(ck, &p("along_dip_min_m"), self.along_dip_min_m);
        ok &= MAP_ALONG_DIP_MAX.check(ck, &p("along_dip_max_m"), s1);
        ok &= MAP_ACROSS_MIN.check(ck, &p("across_min_m"), self.across_min_m);
        ok &= MAP_ACROSS_MAX.check(ck, &p("across_max_m"), self.across_max_m);
        if ok && s1 <= self.along_dip_min_m {
            ck.push(
                p("along_dip_max_m"),
                json!(s1),
                format!("must be above along_dip_min_m = {}", self.along_dip_min_m),
            );
            ok = false;
        }
        if ok && self.across_max_m <= self.across_min_m {
            ck.push(
                p("across_max_m"),
                json!(self.across_max_m),
                format!("must be above across_min_m = {}", self.across_min_m),
            );
            ok = false;
        }
        let Some(runs) = runs else {
            ck.push(
                layout.migration_output("maps"),
                serde_json::to_value(*self).unwrap_or_default(),
                "maps are made over an ensemble: they need monte_carlo",
            );
            return None;
        };
        if !ok {
            return None;
        }
        let cells = u64::from(self.cells_along_dip) * u64::from(self.cells_across);
        if cells > config.max_map_cells {
            ck.push(
                layout.migration_output("maps"),
                json!(cells),
                format!(
                    "{} × {} = {cells} cells, more than the limit {} (max_map_cells)",
                    self.cells_along_dip, self.cells_across, config.max_map_cells
                ),
            );
            return None;
        }
        let work = cells.saturating_mul(runs);
        if work > config.max_map_cell_runs {
            ck.push(
                layout.migration_output("maps"),
                json!(work),
                format!(
                    "{cells} cells × {runs} runs = {work} cell-runs, more than the limit {} \
                     (max_map_cell_runs; up to {BYTES_PER_PASSAGE} bytes each if every run \
                     entered every cell): use fewer cells or runs",
                    config.max_map_cell_runs
                ),
            );
            return None;
        }
        Some(MapGrid {
            along_dip_min: self.along_dip_min_m,
            along_dip_max: s1,
            across_min: self.across_min_m,
            across_max: self.across_max_m,
            cells_along_dip: self.cells_along_dip,
            cells_across: self.cells_across,
        })
    }
}

/// Per-cell maps of an ensemble. Cell (i, j) — i along the dip from `along_dip_min_m`, j across
/// from `across_min_m` — covers [along_dip_min_m + i·cell_along_dip_m, … + cell_along_dip_m] ×
/// [across_min_m + j·cell_across_m, … + cell_across_m] and is element i × cells_across + j of
/// every array. A run passes a cell when its path (the centre projected on the face, see the
/// request's `maps`) enters it; its value there is the largest speed (kinetic energy) it had in
/// the cell. Cells no run reached have 0 passages and null statistics.
#[derive(Debug, Clone, PartialEq, Serialize, ToSchema)]
pub struct MapsOutDto {
    /// Cells along the dip.
    pub cells_along_dip: u32,
    /// Cells across.
    pub cells_across: u32,
    /// Upper edge of the first row, m along the dip.
    pub along_dip_min_m: f64,
    /// Lower edge of the last row, m along the dip.
    pub along_dip_max_m: f64,
    /// First edge across, m.
    pub across_min_m: f64,
    /// Last edge across, m.
    pub across_max_m: f64,
    /// Cell side along the dip, m.
    pub cell_along_dip_m: f64,
    /// Cell side across, m.
    pub cell_across_m: f64,
    /// Runs of the ensemble.
    pub runs: u64,
    /// Runs whose path entered each cell.
    pub passages: Vec<u64>,
    /// Mean over the passing runs of each run's largest speed in the cell, m/s (null: none).
    pub speed_mean_m_s: Vec<Option<f64>>,
    /// 95th percentile (type 7) of the same, m/s (null: none).
    pub speed_p95_m_s: Vec<Option<f64>>,
    /// Mean over the passing runs of each run's largest kinetic energy (translation and
    /// rotation) in the cell, J (null: none).
    pub kinetic_energy_mean_j: Vec<Option<f64>>,
    /// 95th percentile (type 7) of the same, J (null: none).
    pub kinetic_energy_p95_j: Vec<Option<f64>>,
}

impl From<&Maps> for MapsOutDto {
    fn from(m: &Maps) -> Self {
        let g = &m.grid;
        Self {
            cells_along_dip: g.cells_along_dip,
            cells_across: g.cells_across,
            along_dip_min_m: g.along_dip_min,
            along_dip_max_m: g.along_dip_max,
            across_min_m: g.across_min,
            across_max_m: g.across_max,
            cell_along_dip_m: g.cell_along_dip(),
            cell_across_m: g.cell_across(),
            runs: m.runs,
            passages: m.cells.iter().map(|c| c.passages).collect(),
            speed_mean_m_s: m.cells.iter().map(|c| c.speed.map(|s| s.mean)).collect(),
            speed_p95_m_s: m.cells.iter().map(|c| c.speed.map(|s| s.p95)).collect(),
            kinetic_energy_mean_j: m
                .cells
                .iter()
                .map(|c| c.kinetic_energy.map(|s| s.mean))
                .collect(),
            kinetic_energy_p95_j: m
                .cells
                .iter()
                .map(|c| c.kinetic_energy.map(|s| s.p95))
                .collect(),
        }
    }
}
