#[path = "unit/gmsh.rs"]
mod gmsh;
