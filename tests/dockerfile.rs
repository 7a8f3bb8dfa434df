//! Static checks of the Dockerfile (no Docker engine runs in CI): two stages, a release build,
//! a non-root user, port 8080 on all interfaces, the binary copied where the entrypoint runs it,
//! and every copied path present in the repository.

use std::path::Path;

fn dockerfile() -> Vec<String> {
    let text = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("Dockerfile"))
        .expect("Dockerfile exists");
    text.lines()
        .map(str::trim)
        .filter(|l| !l.is_empty() && !l.starts_with('#'))
        .map(String::from)
        .collect()
}

#[test]
fn multi_stage_release_build() {
    let lines = dockerfile();
    let froms: Vec<&String> = lines.iter().filter(|l| l.starts_with("FROM ")).collect();
    assert!(froms.len() >= 2, "multi-stage: {froms:?}");
    assert!(froms[0].ends_with(" AS build"), "first stage named build");
    assert!(
        lines
            .iter()
            .any(|l| l.starts_with("RUN cargo build --release") && l.contains("--locked")),
        "release build with the lock file"
    );
}

#[test]
fn runs_as_non_root_on_port_8080() {
    let lines = dockerfile();
    let last_from = lines.iter().rposition(|l| l.starts_with("FROM ")).unwrap();
    let runtime = &lines[last_from..];
    let user = runtime
        .iter()
        .find(|l| l.starts_with("USER "))
        .expect("USER in the runtime stage");
    let name = user.trim_start_matches("USER ").trim();
    assert!(name != "root" && name != "0", "non-root user, got {name}");
    assert!(runtime.iter().any(|l| l == "EXPOSE 8080"));
    assert!(runtime.iter().any(|l| l == "ENV GANGUE_BIND=0.0.0.0:8080"));
}

#[test]
fn binary_path_and_copied_sources_exist() {
    let lines = dockerfile();
    let copy = lines
        .iter()
        .find(|l| l.starts_with("COPY --from=build"))
        .expect("binary copied from the build stage");
    let parts: Vec<&str> = copy.split_whitespace().collect();
    assert_eq!(parts[2], "/src/target/release/gangue");
    let dest = parts[3];
    let entry = lines
        .iter()
        .find(|l| l.starts_with("ENTRYPOINT"))
        .expect("ENTRYPOINT");
    assert!(
        entry.contains(&format!("\"{dest}\"")),
        "{entry} runs {dest}"
    );
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    for l in lines
        .iter()
        .filter(|l| l.starts_with("COPY ") && !l.contains("--from"))
    {
        let parts: Vec<&str> = l.split_whitespace().collect();
        for src in &parts[1..parts.len() - 1] {
            assert!(root.join(src).exists(), "COPY source {src} is missing");
        }
    }
}
