//! Service endpoints: health, presets, problem types, the page and its static files.

use axum::extract::{Path, State};
use axum::http::{HeaderValue, StatusCode, header};
use axum::response::{Html, IntoResponse, Response};
use include_dir::{Dir, include_dir};
use serde_json::{Value, json};

use crate::http::dto::common::{self, MODEL_VERSION};
use crate::http::dto::{
    column::ColumnRequest,
    impact::ImpactRequest,
    migration,
    migration::MigrationRequest,
    scene::{SceneMonteCarloDto, SceneRequest, SupportRowsDto},
    spalling,
    study::StudyRequest,
};
use crate::http::error::{ApiError, problem_type};
use crate::http::runner::AppState;

/// The page and its assets, embedded at build time (no files needed at run time).
static STATIC: Dir<'_> = include_dir!("$CARGO_MANIFEST_DIR/static");

/// Liveness: answers at once, even while solvers are busy.
#[utoipa::path(get, path = "/healthz", tag = "service",
    responses((status = 200, description = "The service is up", body = crate::http::openapi::Health, example = json!({"status": "ok", "version": "0.1.0"}))))]
pub async fn healthz() -> Response {
    axum::Json(json!({"status": "ok", "version": MODEL_VERSION})).into_response()
}

/// Named defaults (paper Tables 2–4), presets, the study ranges and the service's limits.
///
/// Also the numeric fields' defaults and ranges (`fields`, `migration_fields`) and each route's
/// default request (`defaults`: what `{}` means, derived fields left out; `defaults.objects`: the
/// defaults of objects used only when sent), from which the page fills its forms.
#[utoipa::path(get, path = "/v1/presets", tag = "service",
    responses((status = 200, description = "Tables 2–4, presets, study ranges, limits", body = crate::http::openapi::Presets)))]
pub async fn presets(State(state): State<AppState>) -> Response {
    axum::Json(presets_value(&state)).into_response()
}

fn presets_value(state: &AppState) -> Value {
    let c = &state.config;
    json!({
        "rock": {
            "source": "paper Table 2",
            "density_kg_m3": common::ROCK_DENSITY.value(),
            "elastic_modulus_pa": common::ROCK_ELASTIC_MODULUS.value(),
            "poisson_ratio": common::ROCK_POISSON_RATIO.value(),
            "friction_coefficient": migration::FACE_FRICTION.value(),
            "side_length_m": common::ROCK_SIDE_LENGTH.value(),
            "normal_stiffness_n_m": migration::FACE_NORMAL_STIFFNESS.value(),
            "shear_stiffness_n_m": migration::FACE_SHEAR_STIFFNESS.value(),
            "note": "Table 2 prints normal and tangential stiffness as 1 N/m, which cannot hold a 67.5 kg block; the service uses 1e8 N/m (physics.md §C.3)"
        },
        "face": {
            "source": "paper Table 3",
            "density_kg_m3": 2800.0,
            "dip_deg": migration::FACE_DIP.value(),
            "internal_friction_angle_deg": 30.0,
            "elastic_modulus_pa": 4.38e9,
            "critical_damping_ratio": migration::FACE_CRITICAL_DAMPING.value(),
            "length_m": migration::FACE_LENGTH.value()
        },
        "column": {
            "source": "paper Table 4, hydraulic support ZZ6500/22/48",
            "support_type": "ZZ6500/22/48",
            "first_stage": {
                "outer_diameter_m": common::COLUMN_OUTER_DIAMETER.value(),
                "inner_diameter_m": common::COLUMN_INNER_DIAMETER.value(),
                "length_m": common::COLUMN_LENGTH.value()
            },
            "second_stage": {"outer_diameter_m": 0.18, "inner_diameter_m": 0.16, "length_m": 1.285},
            "elastic_modulus_pa": common::COLUMN_ELASTIC_MODULUS.value(),
            "poisson_ratio": common::COLUMN_POISSON_RATIO.value(),
            "density_kg_m3": common::COLUMN_DENSITY.value(),
            "yield_stress_pa": common::COLUMN_YIELD_STRESS.value(),
            "note": "Table 4's piston and rod diameters are read as outer and inner diameter of the first stage (physics.md §B.1)"
        },
        "fields": fields(common::IMPACT_FIELDS),
        "migration_fields": fields(migration::MIGRATION_FIELDS),
        "defaults": {
            "impact": to_value(&ImpactRequest::default()),
            "column": to_value(&ColumnRequest::default()),
            "migration": to_value(&MigrationRequest::default()),
            "scene": to_value(&SceneRequest::default()),
            "study": to_value(&StudyRequest::default()),
            "spalling": {"zones": to_value(&spalling::table1_zones())},
            "objects": {
                "monte_carlo": to_value(&migration::MonteCarloDto::default()),
                "scene_monte_carlo": to_value(&SceneMonteCarloDto::default()),
                "support_rows": to_value(&SupportRowsDto::default()),
                "floor": {
                    "elevation_property": migration::ELEVATION_PROPERTY,
                    "resolution_m": migration::FLOOR_RESOLUTION.value()
                }
            }
        },
        "presets": {
            "paper": {
                "contact": {"law": "paper", "effective_modulus": "paper"},
                "galerkin": {"mode_shapes": "paper"},
                "column": {"damping_coefficient_n_s_m2": common::COLUMN_DAMPING_COEFFICIENT.value()}
            },
            "recommended": {
                "contact": {"law": "johnson", "effective_modulus": "two_body"},
                "galerkin": {"mode_shapes": "exact"},
                "column": {"damping_ratio": 0.02},
                "model": "coupled"
            },
            "calibrated_damping": {"column": {"damping_coefficient_n_s_m2": 725.0},
                "note": "reproduces the paper's 'stops near 0.6 s' (physics.md §B.6)"}
        },
        "study": {
            "parameters": [
                {"name": "velocity_m_s", "min": 4.0, "max": 6.0},
                {"name": "rock.side_length_m", "min": 0.2, "max": 0.3},
                {"name": "rock.elastic_modulus_pa", "min": 4e9, "max": 6e9},
                {"name": "rock.density_kg_m3", "min": 2000.0, "max": 3000.0}
            ],
            "x_values": [2.0 / 3.0, 0.75, 5.0 / 6.0, 11.0 / 12.0, 1.0]
        },
        "limits": {
            "max_body_bytes": c.max_body_bytes,
            "compute_timeout_s": c.compute_timeout_s,
            "max_concurrent": c.max_concurrent(),
            "max_queue_wait_ms": c.max_queue_wait_ms,
            "header_timeout_s": c.header_timeout_s,
            "body_timeout_s": c.body_timeout_s,
            "body_budget_bytes": c.body_budget_bytes(),
            "solver_threads": c.solver_threads(),
            "max_monte_carlo_runs": c.max_runs,
            "max_samples": c.max_samples,
            "max_curve_points": c.max_curve_points,
            "max_modes": c.max_modes,
            "max_end_time_s": c.max_end_time_s,
            "max_study_points": c.max_study_points,
            "max_batch_items": c.max_batch_items,
            "max_rigid_block_steps": c.max_rigid_steps,
            "max_floor_bytes": c.max_floor_bytes,
            "max_map_cells": c.max_map_cells,
            "max_map_cell_runs": c.max_map_cell_runs,
            "max_design_evaluations": c.max_design_evaluations
        }
    })
}

/// Numeric fields as `/v1/presets` lists them, keyed by JSON Pointer.
fn fields(list: &[(&str, common::NumberField)]) -> Value {
    Value::Object(
        list.iter()
            .map(|(pointer, field)| ((*pointer).to_owned(), field.preset()))
            .collect(),
    )
}

/// A default request as JSON (the DTOs always serialize).
fn to_value<T: serde::Serialize>(v: &T) -> Value {
    serde_json::to_value(v).unwrap_or(Value::Null)
}

/// A short page explaining one problem type (the `type` of error responses).
#[utoipa::path(get, path = "/problems/{code}", tag = "service",
    params(("code" = String, Path, description = "Problem code, e.g. capacity_exceeded")),
    responses((status = 200, description = "HTML explanation", body = String, content_type = "text/html"),
              (status = 404, description = "Unknown code", body = crate::http::openapi::Problem, content_type = "application/problem+json")))]
pub async fn problem(Path(code): Path<String>) -> Response {
    match problem_type(&code) {
        Some(p) => Html(format!(
            "<!doctype html><html lang=\"en\"><head><meta charset=\"utf-8\"><title>{code}</title>\
             <link rel=\"stylesheet\" href=\"/static/style.css\"></head><body><main>\
             <h1>{title}</h1><p><code>type: /problems/{code}</code> · HTTP {status}</p>\
             <p>{expl}</p><p><a href=\"/\">gangue</a> · <a href=\"/docs\">API docs</a></p>\
             </main></body></html>",
            title = p.title,
            status = p.status,
            expl = p.explanation,
        ))
        .into_response(),
        None => ApiError::new("not_found", format!("no problem type `{code}`")).into_response(),
    }
}

/// The page.
pub async fn index() -> Response {
    asset("index.html")
}

/// Files of the page under `/static/`.
pub async fn static_file(Path(path): Path<String>) -> Response {
    asset(&path)
}

fn asset(path: &str) -> Response {
    match STATIC.get_file(path) {
        Some(f) => {
            let mime = mime_guess::from_path(path).first_or_octet_stream();
            let mut res = (StatusCode::OK, f.contents()).into_response();
            if let Ok(v) = HeaderValue::from_str(mime.as_ref()) {
                res.headers_mut().insert(header::CONTENT_TYPE, v);
            }
            res.headers_mut()
                .insert(header::CACHE_CONTROL, HeaderValue::from_static("no-cache"));
            res
        }
        None => ApiError::new("not_found", format!("no file `{path}`")).into_response(),
    }
}
