//! Where each physics parameter sits in a request: the one map from a [`Param`] (physics terms)
//! to the JSON Pointer of the field in the request actually sent.
//!
//! The standalone requests (`/v1/impact`, `/v1/column`, `/v1/migration`) share their field
//! names, so one map serves them all; a batch item or a study nests that pointer under its own
//! prefix. A scene names the same parameters elsewhere (a support's column, `migration_output`,
//! `column_output`), so it has its own map.

use crate::physics::Param;

/// The pointer of a parameter below its object, e.g. `density_kg_m3` below `/rock`.
enum Place {
    /// A field of the request's root.
    Root(&'static str),
    /// A field of the rock object.
    Rock(&'static str),
    /// A field of the column object.
    Column(&'static str),
    /// A field of the column history (`output` of a column request).
    History(String),
    /// A field of the migration output (`output` of a migration request).
    Trajectory(&'static str),
    /// Any other path from the root.
    Path(String),
}

fn place(param: Param) -> Place {
    use Place::{Column, History, Path, Rock, Root, Trajectory};
    match param {
        Param::ImpactVelocity => Root("velocity_m_s"),
        Param::RockSideLength => Rock("side_length_m"),
        Param::RockDensity => Rock("density_kg_m3"),
        Param::RockElasticModulus => Rock("elastic_modulus_pa"),
        Param::RockPoissonRatio => Rock("poisson_ratio"),
        Param::RockRadius => Rock("radius_m"),
        Param::RockCornerRadius => Rock("corner_radius_m"),
        Param::RockDimensions => Rock("dimensions_m"),
        Param::RockVertices => Rock("vertices_m"),
        Param::RockRandomShape => Rock("random"),
        Param::RockRandomVertexCount => Rock("random/vertices"),
        Param::ColumnContactRadius => Column("contact_radius_m"),
        Param::ColumnElasticModulus => Column("elastic_modulus_pa"),
        Param::ColumnPoissonRatio => Column("poisson_ratio"),
        Param::ColumnYieldStress => Column("yield_stress_pa"),
        Param::ColumnLength => Column("length_m"),
        Param::ColumnDampingCoefficient => Column("damping_coefficient_n_s_m2"),
        Param::ColumnDampingRatio => Column("damping_ratio"),
        Param::ContactLaw => Path("/contact/law".into()),
        Param::GalerkinModes => Path("/galerkin/modes".into()),
        Param::ModeShapes => Path("/galerkin/mode_shapes".into()),
        Param::CoupledWindow => Root("end_time_s"),
        Param::InitialMidpointDisplacement => Root("initial_midpoint_displacement_m"),
        Param::HistoryTimes => History("times_s".into()),
        Param::HistoryTime(i) => History(format!("times_s/{i}")),
        Param::HistoryDuration => History("duration_s".into()),
        Param::HistorySamples => History("samples".into()),
        Param::TrajectorySampleInterval => Trajectory("sample_interval_s"),
        Param::Floor => Path("/face/floor".into()),
        Param::FloorMap => Path("/face/floor/map".into()),
        Param::FloorMapOrigin => Path("/face/floor/map/origin_m".into()),
        Param::FloorHeights => Path("/face/floor/heights_m".into()),
        Param::FloorHeightRow(i) => Path(format!("/face/floor/heights_m/{i}")),
        Param::FloorHeight(i, j) => Path(format!("/face/floor/heights_m/{i}/{j}")),
        Param::FloorContours => Path("/face/floor/contours".into()),
        Param::FloorContourPoint(c, k) => Path(format!("/face/floor/contours/{c}/points_m/{k}")),
        Param::FloorResolution => Path("/face/floor/resolution_m".into()),
        Param::ReleaseAcross => Path("/release/across_m".into()),
        Param::ReleasePoint => Path("/release/position_m".into()),
        Param::ReleaseAlongDip => Path("/release/along_dip_m".into()),
        Param::ReleaseZones => Path("/release_zones".into()),
        Param::FaceFriction => Path("/face/friction_coefficient".into()),
        Param::FaceZones => Path("/face/zones".into()),
        Param::ZoneNormalStiffness(i) => Path(format!(
            "/face/zones/materials/{i}/rigid_block/normal_stiffness_n_m"
        )),
        Param::DrawnFriction => Path("/monte_carlo/friction_coefficient".into()),
        Param::FaceNormalStiffness => Path("/face/normal_stiffness_n_m".into()),
        Param::FloorElasticModulus => Path("/face/floor_material/elastic_modulus_pa".into()),
        Param::RigidBlockTimeStep => Path("/rigid_block/time_step_s".into()),
        Param::MonteCarloRuns => Path("/monte_carlo/runs".into()),
    }
}

/// The JSON Pointer of `param` in a standalone request (`/v1/impact`, `/v1/column`,
/// `/v1/migration`); a batch item or study nests it under its own prefix.
#[must_use]
pub fn request_pointer(param: Param) -> String {
    match place(param) {
        Place::Root(f) => format!("/{f}"),
        Place::Rock(f) => format!("/rock/{f}"),
        Place::Column(f) => format!("/column/{f}"),
        Place::History(f) => format!("/output/{f}"),
        Place::Trajectory(f) => format!("/output/{f}"),
        Place::Path(p) => p,
    }
}

/// The JSON Pointer of `param` in a `/v1/scene` request. `support` is the pointer of the support
/// object the failing stage concerns (`/supports/2` or `/support_rows`), if any.
///
/// The scene's impact speed is `impact_velocity_m_s` when sent (else the migration's, which no
/// field names); its coupled window is the default one, chosen by `column_model`.
#[must_use]
pub fn scene_pointer(param: Param, support: Option<&str>) -> String {
    match param {
        Param::ImpactVelocity => return "/impact_velocity_m_s".into(),
        Param::CoupledWindow => return "/column_model".into(),
        _ => {}
    }
    match place(param) {
        Place::Root(f) => format!("/{f}"),
        Place::Rock(f) => format!("/rock/{f}"),
        Place::Column(f) => format!("{}/column/{f}", support.unwrap_or("/supports/0")),
        Place::History(f) => format!("/column_output/{f}"),
        Place::Trajectory(f) => format!("/migration_output/{f}"),
        Place::Path(p) => p,
    }
}

/// The request whose layout the pointers of a shared check follow: `/v1/migration` and
/// `/v1/column` check their output objects at `/output`, a scene checks the same objects at
/// `/migration_output` and `/column_output`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Layout {
    /// A standalone request (`/v1/impact`, `/v1/column`, `/v1/migration`, a batch item's).
    Request,
    /// A `/v1/scene` request.
    Scene,
}

impl Layout {
    /// The JSON Pointer of `param` in this layout (a scene's column: the first support's).
    #[must_use]
    pub fn pointer(self, param: Param) -> String {
        match self {
            Self::Request => request_pointer(param),
            Self::Scene => scene_pointer(param, None),
        }
    }

    /// The JSON Pointer of the migration output option `field` (no physics parameter names it,
    /// e.g. `runs_csv`): `/output/{field}` or `/migration_output/{field}`.
    #[must_use]
    pub fn migration_output(self, field: &str) -> String {
        match self {
            Self::Request => format!("/output/{field}"),
            Self::Scene => format!("/migration_output/{field}"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_scene_names_the_support_and_its_own_output_objects() {
        assert_eq!(
            scene_pointer(Param::ColumnLength, Some("/supports/2")),
            "/supports/2/column/length_m"
        );
        assert_eq!(
            scene_pointer(Param::HistoryTime(4), None),
            "/column_output/times_s/4"
        );
        assert_eq!(
            scene_pointer(Param::TrajectorySampleInterval, None),
            "/migration_output/sample_interval_s"
        );
        assert_eq!(request_pointer(Param::HistoryTime(4)), "/output/times_s/4");
        assert_eq!(request_pointer(Param::RockDensity), "/rock/density_kg_m3");
        assert_eq!(request_pointer(Param::CoupledWindow), "/end_time_s");
    }

    #[test]
    fn the_output_objects_are_named_by_the_layout() {
        let (r, s) = (Layout::Request, Layout::Scene);
        assert_eq!(r.pointer(Param::HistoryDuration), "/output/duration_s");
        assert_eq!(
            s.pointer(Param::HistoryDuration),
            "/column_output/duration_s"
        );
        assert_eq!(
            s.pointer(Param::TrajectorySampleInterval),
            "/migration_output/sample_interval_s"
        );
        assert_eq!(r.migration_output("runs_csv"), "/output/runs_csv");
        assert_eq!(s.migration_output("runs_csv"), "/migration_output/runs_csv");
    }
}
