//! The committed `openapi/openapi.json` must equal the document the code generates.
//! Regenerate with `GANGUE_UPDATE_OPENAPI=1 cargo test --test openapi_drift`.

use std::path::Path;

#[test]
fn committed_openapi_matches_the_code() {
    let generated = gangue::http::openapi::openapi_json();
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("openapi/openapi.json");
    if std::env::var_os("GANGUE_UPDATE_OPENAPI").is_some() {
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(&path, &generated).unwrap();
    }
    let committed = std::fs::read_to_string(&path).unwrap_or_default();
    assert!(
        committed == generated,
        "openapi/openapi.json is out of date: run GANGUE_UPDATE_OPENAPI=1 cargo test --test openapi_drift"
    );
}

#[test]
fn every_request_field_documents_its_range_or_default() {
    let doc: serde_json::Value =
        serde_json::from_str(&gangue::http::openapi::openapi_json()).unwrap();
    let schemas = doc["components"]["schemas"].as_object().unwrap();
    for name in ["ImpactRequest", "RockDto", "ColumnDto", "ContactDto"] {
        let s = &schemas[name];
        for (field, prop) in s["properties"]
            .as_object()
            .unwrap_or_else(|| panic!("{name}"))
        {
            let p = prop.as_object().unwrap();
            let has_doc = p.contains_key("description")
                || prop["allOf"].is_array()
                || prop["oneOf"].is_array()
                || prop["$ref"].is_string();
            assert!(has_doc, "{name}.{field} has no description");
        }
    }
    // Every scalar request field carries a description and an example.
    for (name, schema) in schemas {
        if !(name.ends_with("Request") || name.ends_with("Dto")) || name.contains("History") {
            continue;
        }
        let request_side = doc["paths"]
            .as_object()
            .unwrap()
            .values()
            .any(|p| p.to_string().contains(&format!("schemas/{name}\"")))
            || [
                "RockDto",
                "ColumnDto",
                "ContactDto",
                "FaceDto",
                "FloorDto",
                "ReleaseDto",
                "MonteCarloDto",
                "DistributionDto",
                "GalerkinDto",
                "ColumnOutputDto",
                "LumpedMassDto",
                "RigidBlockDto",
                "MigrationOutputDto",
                "ImpactOutputDto",
                "RandomShapeDto",
                "ContourDto",
            ]
            .contains(&name.as_str());
        if !request_side {
            continue;
        }
        for (field, prop) in schema["properties"].as_object().into_iter().flatten() {
            if prop.get("oneOf").is_some() || prop.get("$ref").is_some() {
                continue;
            }
            assert!(
                prop.get("description").is_some(),
                "{name}.{field}: no description"
            );
            assert!(prop.get("example").is_some(), "{name}.{field}: no example");
        }
    }
    let v = &schemas["ImpactRequest"]["properties"]["velocity_m_s"];
    assert_eq!(v["default"], 5.0);
    assert_eq!(v["maximum"], 1000.0);
    assert_eq!(v["exclusiveMinimum"], 0.0);
}
