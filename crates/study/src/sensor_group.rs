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
    /// The mesh file's number of each mesh node, when the group's last column is the label
    /// of the node (0-based index) in the `mbs` column before it: a largest-von-Mises sensor
    /// of a part read from a mesh file, so that users read the node as their deck numbers it.
    pub node_labels: Option<Vec<u64>>,
}

impl SensorGroup {
    /// The group's columns from the values of its `mbs` sensors, in order: those values, and
    /// with [`Self::node_labels`] the label of the node in the last of them (NaN for a node
    /// without one).
    pub fn values(&self, mbs_values: impl IntoIterator<Item = f64>) -> Vec<f64> {
        let mut values: Vec<f64> = mbs_values.into_iter().collect();
        if let Some(labels) = &self.node_labels {
            let label = values
                .last()
                .filter(|k| k.is_finite() && **k >= 0.0)
                .and_then(|&k| labels.get(k as usize))
                .map_or(f64::NAN, |&l| l as f64);
            values.push(label);
        }
        values
    }
}
