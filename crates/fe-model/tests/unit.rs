#![allow(non_snake_case)]
//! fe-model tests, one binary. Each module says what belongs in it.

mod unit {
    /// Dof numbering, elimination, assembly invariants and the errors of bad input.
    mod assembly;
    /// Element level for the 3D beam: symmetry, rigid null space, mass, independent
    /// quadrature of the shape functions, one-element cantilevers, sections, errors.
    mod beam2;
    /// Structure-level beam tests against validation problem A1/A2: statics to round-off,
    /// frequencies within 0.1 % and converging, the Timoshenko frequency equation.
    mod beam_structure;
    /// Shared fixtures: materials, sections, beam models along skewed axes.
    pub mod common;
    /// Geometric stiffness: element energies against direct quadrature, symmetry, rigid
    /// motions, the projected tensor; Euler buckling of beam and hex20 columns.
    mod geometric;
    /// gmsh reader: fixtures in four encodings agree, inline parse cases, node orderings
    /// against gmsh's reference elements, located errors, no panic on random/cut/mutated input.
    mod gmsh;
    /// Abaqus and Nastran readers: the fixtures give gmsh's cells and frequencies, sets,
    /// materials, spiders and supports; inline cases; located errors; no panic on
    /// random/cut/mutated input.
    mod import;
    /// RBE2/RBE3 interface nodes on solids: rigid patch, no added stiffness, bad sets.
    mod interface;
    /// Mass and centre of mass of a model against the analytic box and cylinder.
    mod mass_properties;
    /// Fill-reducing orderings: nested dissection is a valid permutation, solves as AMD does,
    /// and gives a smaller factor on a 3D block.
    mod ordering;
    /// Quadrature rules: exactness degrees.
    mod quadrature;
    /// Solid elements (tet4, tet10, hex8, hex20, wedge6): shape functions, patch tests, rigid
    /// modes, mass, box meshes, solid models; cantilever vs Timoshenko; tet4 locking.
    mod solid;
    /// Stress recovery: the patch test of nodal stresses on every solid kind (one distorted
    /// element, a distorted mesh), exact extrapolation of linear stresses on quadratic kinds,
    /// beam section forces against the analytic cantilever under tip load and gravity.
    mod stress;
    /// Unit systems of decks: a factor per quantity, the plausibility check, mm-t-s twins of
    /// the Abaqus and Nastran fixtures read with and without their units.
    mod units;
}
