//! Rebuilds the binary when the embedded page under `static/` changes, and records the git
//! commit it was built from (if any) for the build id of sharded computations.
use std::process::Command;

fn git(args: &[&str]) -> Option<String> {
    let out = Command::new("git").args(args).output().ok()?;
    out.status
        .success()
        .then(|| String::from_utf8_lossy(&out.stdout).trim().to_string())
}

fn main() {
    println!("cargo:rerun-if-changed=static");
    println!("cargo:rerun-if-changed=src");
    println!("cargo:rerun-if-changed=Cargo.toml");
    println!("cargo:rerun-if-changed=Cargo.lock");
    println!("cargo:rerun-if-env-changed=GANGUE_GIT_HASH");
    // A commit hash only when the sources are exactly that commit; otherwise (no git, or local
    // changes) the build id is a hash of the binary itself, computed at run time.
    let hash = std::env::var("GANGUE_GIT_HASH").ok().or_else(|| {
        if let Some(head) = git(&["rev-parse", "--git-path", "HEAD"]) {
            println!("cargo:rerun-if-changed={head}");
        }
        let commit = git(&["rev-parse", "HEAD"])?;
        let dirty = git(&[
            "status",
            "--porcelain",
            "--untracked-files=no",
            "--",
            "src",
            "static",
            "Cargo.toml",
            "Cargo.lock",
            "build.rs",
        ])?;
        dirty.is_empty().then_some(commit)
    });
    println!(
        "cargo:rustc-env=GANGUE_GIT_HASH={}",
        hash.unwrap_or_default()
    );
}
