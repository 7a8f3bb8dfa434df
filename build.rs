//! Rebuilds the binary when the embedded page under `static/` changes.
fn main() {
    println!("cargo:rerun-if-changed=static");
}
