#[path = "unit/beam2.rs"]
mod beam2;
