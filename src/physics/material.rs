//! Plain parameter structs shared by the solvers: the rock, the column section, the contact model.
//!
//! All fields are SI. Defaults are the paper's base case (physics.md §0). Range checks live in the
//! web layer (api.md); solvers assume in-range values and check only model validity.

use std::f64::consts::PI;

/// Shape of the falling block as far as contact and mass are concerned.
#[derive(Debug, Clone, PartialEq)]
pub enum RockShape {
    /// Cube of side `Rock::side_length`.
    Cube,
    /// Sphere of the given radius, m.
    Sphere {
        /// Radius, m.
        radius: f64,
    },
    /// Rectangular block with edges `[a, b, c]`, m.
    Cuboid {
        /// Edge lengths, m.
        dimensions: [f64; 3],
    },
    /// Polyhedron inscribed in the ellipsoid of full axes `[a, b, c]` along x, y, z (the
    /// block's measured dimensions), scaled to the ellipsoid's volume π a b c / 6.
    Ellipsoid {
        /// Full axes (dimensions), m.
        dimensions: [f64; 3],
    },
    /// Convex polyhedron given by points (its hull), m, relative to any origin.
    Polyhedron {
        /// Vertex coordinates, m.
        vertices: Vec<[f64; 3]>,
    },
    /// Random convex polyhedron by the ellipsoid method.
    RandomPolyhedron {
        /// Semi-axes of the ellipsoid, m.
        semi_axes: [f64; 3],
        /// Number of points drawn on the ellipsoid.
        vertices: usize,
        /// Seed of the shape generator.
        seed: u64,
    },
}

/// The falling rock block.
#[derive(Debug, Clone, PartialEq)]
pub struct Rock {
    /// Shape of the block (default: cube).
    pub shape: RockShape,
    /// Cube side L = contact length on the column, m (default 0.3).
    pub side_length: f64,
    /// Density ρ, kg/m³ (default 2500).
    pub density: f64,
    /// Young's modulus E, Pa (default 5e9).
    pub elastic_modulus: f64,
    /// Poisson ratio ν (default 0.28).
    pub poisson_ratio: f64,
    /// Rounded-corner radius r_c for the Hertz point law, m (default min(0.02, L/2)).
    pub corner_radius: f64,
}

/// The documented defaults of the impact case (api.md, the shared request objects): the
/// `Default`s below and the request fields' defaults are these constants.
pub mod defaults {
    /// Normal impact speed v, m/s.
    pub const VELOCITY: f64 = 5.0;
    /// Rock side length L, m.
    pub const ROCK_SIDE_LENGTH: f64 = 0.3;
    /// Rock density ρ, kg/m³.
    pub const ROCK_DENSITY: f64 = 2500.0;
    /// Rock Young's modulus E, Pa.
    pub const ROCK_ELASTIC_MODULUS: f64 = 5.0e9;
    /// Rock Poisson's ratio ν, dimensionless.
    pub const ROCK_POISSON_RATIO: f64 = 0.28;
    /// Column outer diameter D₁, m.
    pub const COLUMN_OUTER_DIAMETER: f64 = 0.250;
    /// Column inner diameter D₂, m.
    pub const COLUMN_INNER_DIAMETER: f64 = 0.235;
    /// Column length l, m.
    pub const COLUMN_LENGTH: f64 = 1.310;
    /// Column Young's modulus E_s, Pa.
    pub const COLUMN_ELASTIC_MODULUS: f64 = 208e9;
    /// Column Poisson's ratio ν_s, dimensionless.
    pub const COLUMN_POISSON_RATIO: f64 = 0.3;
    /// Column density ρ_s, kg/m³.
    pub const COLUMN_DENSITY: f64 = 7850.0;
    /// Column yield stress σ_y, Pa.
    pub const COLUMN_YIELD_STRESS: f64 = 345e6;
    /// Column damping coefficient c, N·s/m².
    pub const COLUMN_DAMPING_COEFFICIENT: f64 = 1.0;
    /// Largest default corner radius of the rock, m: the default r_c is min(this, L/2).
    pub const ROCK_CORNER_RADIUS: f64 = 0.02;

    /// The default corner radius min(0.02, L/2) of a rock of side `side_length` (m), m.
    #[must_use]
    pub fn corner_radius(side_length: f64) -> f64 {
        ROCK_CORNER_RADIUS.min(side_length / 2.0)
    }
}

impl Default for Rock {
    fn default() -> Self {
        Self {
            shape: RockShape::Cube,
            side_length: defaults::ROCK_SIDE_LENGTH,
            density: defaults::ROCK_DENSITY,
            elastic_modulus: defaults::ROCK_ELASTIC_MODULUS,
            poisson_ratio: defaults::ROCK_POISSON_RATIO,
            corner_radius: defaults::corner_radius(defaults::ROCK_SIDE_LENGTH),
        }
    }
}

impl Rock {
    /// Volume of the block, m³, for the shapes whose volume is known in closed form
    /// (cube, sphere, cuboid); polyhedra report their hull volume through the migration shape
    /// module, and fall back to the cube here.
    #[must_use]
    pub fn volume(&self) -> f64 {
        match &self.shape {
            RockShape::Sphere { radius } => 4.0 / 3.0 * PI * radius.powi(3),
            RockShape::Cuboid { dimensions } => dimensions.iter().product(),
            RockShape::Ellipsoid { dimensions } => PI / 6.0 * dimensions.iter().product::<f64>(),
            _ => self.side_length.powi(3),
        }
    }

    /// Mass of the block, kg (cube ρL³, sphere 4/3πr³ρ, cuboid ρabc, ellipsoid ρπabc/6).
    #[must_use]
    pub fn mass(&self) -> f64 {
        self.density * self.volume()
    }
}

/// Viscous damping of the column: a coefficient per unit length, or the mode-1 damping ratio.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Damping {
    /// c, N·s/m² (the paper's value is 1.0).
    Coefficient(f64),
    /// ζ₁ of the exact mode 1, converted to c by c = 2ζ₁√(K₁M₁)/l (physics.md §B.6).
    Ratio(f64),
}

/// The struck hydraulic-support column: a clamped–clamped tube (paper Table 4, first stage).
#[derive(Debug, Clone, PartialEq)]
pub struct Column {
    /// Outer diameter D₁, m (default 0.250).
    pub outer_diameter: f64,
    /// Inner diameter D₂, m (default 0.235; 0 = solid).
    pub inner_diameter: f64,
    /// Length between clamps l, m (default 1.310).
    pub length: f64,
    /// Young's modulus E_s, Pa (default 208e9).
    pub elastic_modulus: f64,
    /// Poisson ratio ν_s (default 0.3).
    pub poisson_ratio: f64,
    /// Density ρ_s, kg/m³ (default 7850).
    pub density: f64,
    /// Yield stress, Pa (default 345e6, 16Mn steel).
    pub yield_stress: f64,
    /// Radius R of the cylinder at the contact, m (default D₁/2).
    pub contact_radius: f64,
    /// Damping (default: c = 1 N·s/m², the paper's value).
    pub damping: Damping,
}

impl Default for Column {
    fn default() -> Self {
        Self {
            outer_diameter: defaults::COLUMN_OUTER_DIAMETER,
            inner_diameter: defaults::COLUMN_INNER_DIAMETER,
            length: defaults::COLUMN_LENGTH,
            elastic_modulus: defaults::COLUMN_ELASTIC_MODULUS,
            poisson_ratio: defaults::COLUMN_POISSON_RATIO,
            density: defaults::COLUMN_DENSITY,
            yield_stress: defaults::COLUMN_YIELD_STRESS,
            contact_radius: defaults::COLUMN_OUTER_DIAMETER / 2.0,
            damping: Damping::Coefficient(defaults::COLUMN_DAMPING_COEFFICIENT),
        }
    }
}

/// Cross-section properties of the column (physics.md §B.1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Section {
    /// Area A = π(D₁² − D₂²)/4, m².
    pub area: f64,
    /// Second moment I = π(D₁⁴ − D₂⁴)/64, m⁴.
    pub second_moment: f64,
    /// Mass per length μ = ρ_s A, kg/m.
    pub mass_per_length: f64,
    /// Rotary inertia per length J₀ = ρ_s I, kg·m.
    pub rotary_inertia: f64,
    /// Bending stiffness EI = E_s I, N·m².
    pub bending_stiffness: f64,
}

impl Column {
    /// Section properties of the hollow tube.
    #[must_use]
    pub fn section(&self) -> Section {
        let (d1, d2) = (self.outer_diameter, self.inner_diameter);
        let area = PI * (d1 * d1 - d2 * d2) / 4.0;
        let second_moment = PI * (d1.powi(4) - d2.powi(4)) / 64.0;
        Section {
            area,
            second_moment,
            mass_per_length: self.density * area,
            rotary_inertia: self.density * second_moment,
            bending_stiffness: self.elastic_modulus * second_moment,
        }
    }
}

/// Force–approach law of the rock on the column.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ContactLaw {
    /// The paper's logarithmic line contact, reference length L (physics.md §A.3).
    Paper,
    /// Johnson's cylinder compliance (physics.md §A.5), recommended.
    Johnson,
    /// Hertz point contact of a rounded corner r_c on the cylinder (physics.md §A.7).
    HertzPoint,
}

/// Which effective modulus E* the contact uses (physics.md §A.2).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ModulusConvention {
    /// E/(1 − ν²) of the rock only (the paper).
    Paper,
    /// 1/E* = (1 − ν²)/E + (1 − ν_s²)/E_s (recommended).
    TwoBody,
}

/// How the contact is modelled.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactModel {
    /// Force–approach law (default: paper).
    pub law: ContactLaw,
    /// Effective-modulus convention (default: paper).
    pub modulus: ModulusConvention,
    /// Exact elliptical Hertz κ (true, default) or the equivalent-radius form.
    pub hertz_exact: bool,
}

impl Default for ContactModel {
    fn default() -> Self {
        Self {
            law: ContactLaw::Paper,
            modulus: ModulusConvention::Paper,
            hertz_exact: true,
        }
    }
}

/// A normal impact of the rock at the column's midpoint.
#[derive(Debug, Clone, PartialEq)]
pub struct ImpactCase {
    /// Normal impact speed v, m/s (default 5).
    pub velocity: f64,
    /// The rock.
    pub rock: Rock,
    /// The column.
    pub column: Column,
    /// The contact model.
    pub contact: ContactModel,
}

impl Default for ImpactCase {
    fn default() -> Self {
        Self {
            velocity: defaults::VELOCITY,
            rock: Rock::default(),
            column: Column::default(),
            contact: ContactModel::default(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// physics.md §B.1 base-case section, to 1e-9.
    #[test]
    fn base_section_matches_spec_table() {
        let s = Column::default().section();
        let rel = |a: f64, b: f64| ((a - b) / b).abs();
        assert!(rel(s.area, 5.713771639e-3) < 1e-9);
        assert!(rel(s.second_moment, 4.204086039e-5) < 1e-9);
        assert!(rel(s.mass_per_length, 44.85310736) < 1e-9);
        assert!(rel(s.rotary_inertia, 0.3300207540) < 1e-9);
        assert!(rel(s.bending_stiffness, 8.744498960e6) < 1e-9);
    }

    #[test]
    fn base_rock_mass_is_67_5_kg() {
        assert!((Rock::default().mass() - 67.5).abs() < 1e-12);
    }
}
