//! The output wing: what the analyses stream ([`observer`]) and where it lands ([`folder`]:
//! CSV, VTU/PVD, PNG and the summary of a results folder).
//!
//! | module | what it holds |
//! |---|---|
//! | [`observer`] | the output observer trait, result tables, the in-memory [`observer::Recorder`] |
//! | [`folder`] | the results folder observer: CSV, VTU/PVD, PNG, summary |
//! | [`summary`] | CSV text, summary types, results-folder layout, atomic writes |
//! | [`vtu`] | VTK XML unstructured grids and `.pvd` collections |
//! | [`view`] | the data of the results page `view.html` (bodies, poses, sensors) |

pub mod folder;
pub mod observer;
pub mod summary;
pub mod view;
pub mod vtu;
