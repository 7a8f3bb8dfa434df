//! gangue server binary.
fn main() {}
