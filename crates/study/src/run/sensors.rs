//! The sensors of the study picked out of the `mbs` sensor record: their columns and the
//! stream of samples to the observer.

use crate::build::BuiltMechanism;
use crate::error::BoxError;
use crate::output::observer::{Observer, SensorStream};
use crate::sensor_group::SensorGroup;
use mbs::SensorRecord;
use std::collections::HashMap;

/// Per group: the indices in `record` (for a record of `System::sensor_record`, in
/// `Model::sensors`) of the `mbs` sensors it is made of, in order. A group naming a sensor
/// the record lacks is an error naming both.
pub fn sensor_indices(groups: &[SensorGroup], record: &SensorRecord) -> Result<Vec<Vec<usize>>, BoxError> {
    let mut index: HashMap<&str, usize> = HashMap::with_capacity(record.names.len());
    for (k, n) in record.names.iter().enumerate() {
        index.entry(n.as_str()).or_insert(k);
    }
    groups
        .iter()
        .map(|g| {
            g.mbs_names
                .iter()
                .map(|n| {
                    index
                        .get(n.as_str())
                        .copied()
                        .ok_or_else(|| format!("sensor '{}': the model has no sensor '{n}'", g.name).into())
                })
                .collect()
        })
        .collect()
}

/// Per group: its columns in a row of `record` (the `mbs` sensors it is made of, in order;
/// errors as `sensor_indices`).
pub fn sensor_columns(groups: &[SensorGroup], record: &SensorRecord) -> Result<Vec<Vec<usize>>, BoxError> {
    let mut offsets = Vec::with_capacity(record.widths.len());
    let mut at = 0;
    for w in &record.widths {
        offsets.push(at);
        at += w;
    }
    Ok(sensor_indices(groups, record)?
        .into_iter()
        .map(|ks| {
            ks.into_iter()
                .flat_map(|k| offsets[k]..offsets[k] + record.widths[k])
                .collect()
        })
        .collect())
}

/// The sensors of the study picked out of the rows of an `mbs::SensorRecord` and sent to
/// the observer; the last sample is kept for the report.
pub struct SensorSampler {
    /// Per group: its columns in a record row.
    columns: Vec<Vec<usize>>,
    /// The groups, which add columns derived from the record's (node labels).
    groups: Vec<SensorGroup>,
    /// The abscissa and values of the last sample.
    pub last: Option<(f64, Vec<Vec<f64>>)>,
}

impl SensorSampler {
    /// Starts the sensor stream of `groups` (columns named in `record`), with `x_label` as the
    /// abscissa.
    pub fn start(
        obs: &mut dyn Observer,
        groups: &[SensorGroup],
        record: &mbs::SensorRecord,
        x_label: &str,
        plots: bool,
    ) -> Result<Self, BoxError> {
        let columns = sensor_columns(groups, record)?;
        obs.sensors(&SensorStream { x_label, groups, plots })?;
        Ok(Self {
            columns,
            groups: groups.to_vec(),
            last: None,
        })
    }

    /// Sends the last row of `record` (abscissa `x`).
    pub fn sample(&mut self, obs: &mut dyn Observer, x: f64, record: &mbs::SensorRecord) -> Result<(), BoxError> {
        match record.rows.last() {
            Some(row) => self.sample_row(obs, x, row),
            None => Ok(()),
        }
    }

    /// Sends rows `rows` of `record`, each at its time, all of them even when the user asks
    /// to stop (the folder writes a row, then says so: the first such stop is returned after
    /// the last row).
    pub fn sample_rows(
        &mut self,
        obs: &mut dyn Observer,
        record: &mbs::SensorRecord,
        rows: std::ops::Range<usize>,
    ) -> Result<(), BoxError> {
        let mut stop = None;
        for r in rows {
            match self.sample_row(obs, record.times[r], &record.rows[r]) {
                Ok(()) => {}
                Err(e) if e.is::<crate::interrupt::Interrupted>() => {
                    stop.get_or_insert(e);
                }
                Err(e) => return Err(e),
            }
        }
        stop.map_or(Ok(()), Err)
    }

    /// Sends one row (abscissa `x`).
    fn sample_row(&mut self, obs: &mut dyn Observer, x: f64, row: &[f64]) -> Result<(), BoxError> {
        let values: Vec<Vec<f64>> = self
            .columns
            .iter()
            .zip(&self.groups)
            .map(|(cols, g)| g.values(cols.iter().map(|&c| row[c])))
            .collect();
        obs.sample(x, &values)?;
        self.last = Some((x, values));
        Ok(())
    }
}

/// The last value of every sensor, for the report.
pub fn report_last(report: &mut Vec<String>, b: &BuiltMechanism, files: &SensorSampler) {
    let Some((x, rows)) = &files.last else {
        return;
    };
    for (g, row) in b.groups.iter().zip(rows) {
        let values: Vec<String> = g
            .columns
            .iter()
            .zip(row)
            .map(|(c, v)| format!("{c} = {v:.6e}"))
            .collect();
        report.push(format!("sensor '{}' at {x:.6}: {}", g.name, values.join(", ")));
    }
}
