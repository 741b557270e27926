//! The sensors of a study as the observer sees them: plain data that `build` makes and
//! `run` and `output` read; it uses nothing of the crate, so that `build` needs nothing of
//! `output`.

/// One sensor of the study: the `mbs` sensors it is made of and its columns, each named with
/// its unit (`"deflection [m]"`).
#[derive(Clone, Debug)]
pub struct SensorGroup {
    pub name: String,
    pub mbs_names: Vec<String>,
    pub columns: Vec<String>,
}
