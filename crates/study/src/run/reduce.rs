//! The cached reduction service: a part reduced by Craig-Bampton, or read from the cache
//! ([`super::cache`]) when the same mesh and settings were reduced before; the bodies of the
//! mechanism reduced once per part; `flexmbs reduce`.

use super::options::Options;
use crate::build::{BuiltMechanism, ReducedBodies};
use crate::error::{BoxError, ResultExt};
use crate::input::part::{Built, Part, Reduction};
use crate::input::validate::mechanism::BodySource;
use crate::input::validate::Study;
use crate::mesh::VtuMesh;
use crate::output::observer::{Observer, Progress};
use fe_model::DofMap;
use reduction::{CbSettings, ReducedBody};
use serde_json::json;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

pub fn free_dofs(part: &Part, built: &Built) -> Result<usize, BoxError> {
    Ok(DofMap::new(&built.model)
        .context(|| format!("part '{}': cannot number the dofs", part.name))?
        .n_free())
}

/// A part reduced through the cache.
pub struct Reduced {
    /// Shared with the model and the system built from it (a large solid's shapes are
    /// hundreds of MB).
    pub body: std::sync::Arc<ReducedBody>,
    pub built: Built,
    /// The cache file.
    pub file: PathBuf,
    pub from_cache: bool,
    pub free_dofs: usize,
}

/// Reduces `part` of `study` (which has a reduction), or reads it from the cache
/// (`run::cache`) when the same mesh and settings were reduced before. A mode count the part
/// cannot give is located at its `reduction.modes` in the study file.
pub fn reduce_part(study: &Study, part: &Part, cache: &Path, obs: &mut dyn Observer) -> Result<Reduced, BoxError> {
    let Some(reduction) = &part.reduction else {
        return Err(format!("part '{}' has no [parts.reduction]", part.name).into());
    };
    let built = part
        .build_for_reduction(reduction)
        .context(|| format!("part '{}': cannot build the FE model", part.name))?;
    let n_free = free_dofs(part, &built)?;
    let key = super::cache::key(part, &built, reduction)
        .context(|| format!("part '{}': cannot hash its inputs", part.name))?;
    let file = super::cache::path(cache, &part.name, &key);
    if let Some(mut body) = from_cache(part, &file, &key, obs) {
        // A cache file written before labels were kept has none: the key is the same.
        label_interfaces(part, &mut body);
        return Ok(Reduced {
            body: body.into(),
            built,
            file,
            from_cache: true,
            free_dofs: n_free,
        });
    }
    announce(part, reduction, &built, n_free, obs);
    let t = Instant::now();
    let settings = cb_settings(reduction, &built);
    let mut progress = |stage: reduction::Stage| reduction_stage(&part.name, stage, obs);
    let mut body = reduction::reduce_with_progress(
        &built.model,
        &part.name,
        &built.interfaces,
        &settings,
        fe_model::FillOrdering::Auto,
        &mut progress,
    )
    .map_err(|e| -> BoxError {
        // A mode count the part cannot give is the study's to change: located at the key.
        let message = if let reduction::ReductionError::TooManyModes { .. } = e {
            let at = part.path.key("reduction").key("modes");
            format!("{}: {at}: part '{}'", study.location(&at), part.name)
        } else {
            format!("part '{}': Craig-Bampton reduction failed", part.name)
        };
        Box::new(crate::error::Context {
            message,
            source: e.into(),
        })
    })?;
    obs.progress(&Progress::Finished);
    label_interfaces(part, &mut body);
    // The checks every body passes before use (a body read back from the cache passes them
    // on reading).
    reduction::check_body(&body, &file).context(|| format!("part '{}': the reduced body is refused", part.name))?;
    obs.progress(&Progress::Info(format!(
        "part '{}': reduced in {:.2} s to {} coordinates ({} interfaces, {} modes)",
        part.name,
        t.elapsed().as_secs_f64(),
        body.n_coordinates(),
        body.interfaces.len(),
        body.n_modes
    )));
    save(part, &body, cache, &file, &key, obs)?;
    Ok(Reduced {
        body: body.into(),
        built,
        file,
        from_cache: false,
        free_dofs: n_free,
    })
}

/// Gives each interface of `body` on a node of the part's mesh file that node's number in the
/// file. Generated meshes have no file numbers (their tags are positions), so their bodies keep
/// no labels and their bytes; the nodes the program adds (spider and auxiliary nodes) come
/// after the file's nodes and have no number in the file.
fn label_interfaces(part: &Part, body: &mut ReducedBody) {
    for i in &mut body.interfaces {
        i.node_label = part.deck_label(i.node as usize);
    }
}

/// The body of `part` in the cache file `file` when the file records `key` and holds that
/// part; a cache file that cannot be used is reported, and reduced again.
fn from_cache(part: &Part, file: &Path, key: &str, obs: &mut dyn Observer) -> Option<ReducedBody> {
    if !file.is_file() {
        return None;
    }
    let recorded = super::cache::lookup(file, key);
    if recorded.is_none() {
        obs.progress(&Progress::Warning(format!(
            "cache file {} does not record the inputs of this reduction (or was changed); reducing again",
            file.display()
        )));
    }
    match recorded.map(|bytes| reduction::file::from_bytes(&bytes, file)) {
        None => None,
        Some(Ok(body)) if body.name == part.name => {
            obs.progress(&Progress::Info(format!(
                "part '{}': reduced body found in the cache ({}): same mesh and settings, not reducing again",
                part.name,
                file.display()
            )));
            Some(body)
        }
        Some(Ok(_)) => {
            obs.progress(&Progress::Warning(format!(
                "cache file {} holds another body; reducing again",
                file.display()
            )));
            None
        }
        Some(Err(e)) => {
            obs.progress(&Progress::Warning(format!(
                "cannot use the cached body ({e}); reducing again"
            )));
            None
        }
    }
}

/// Says what `reduction` of `part` (`n_free` dofs, built as `built`) is about to do.
fn announce(part: &Part, reduction: &Reduction, built: &Built, n_free: usize, obs: &mut dyn Observer) {
    let modes = match reduction.modes {
        reduction::ModeSelection::StaticOnly => "static modes only".to_string(),
        reduction::ModeSelection::Count(m) => format!("{m} fixed-interface modes"),
        reduction::ModeSelection::CutoffHz(f) => format!("fixed-interface modes below {f} Hz"),
    };
    obs.progress(&Progress::Info(format!(
        "part '{}': reducing {n_free} dofs to {} interfaces{} and {modes}{}{}{} ...",
        part.name,
        built.interfaces.len(),
        if built.auxiliary.is_some() {
            " + the auxiliary node"
        } else {
            ""
        },
        if reduction.inertia_correction {
            " + the static correction for the interfaces' inertia"
        } else {
            ""
        },
        if reduction.planar {
            ", planar (in-plane modes)"
        } else {
            ""
        },
        if reduction.geometric_stiffening {
            ", with geometric stiffening"
        } else {
            ""
        }
    )));
}

/// The Craig-Bampton settings of `reduction` on the model `built`.
fn cb_settings(reduction: &Reduction, built: &Built) -> CbSettings {
    let mut settings = CbSettings::new(reduction.modes);
    settings.keep_mesh_shapes = reduction.keep_mesh_shapes;
    settings.auxiliary_node = built.auxiliary;
    settings.geometric_stiffening = reduction.geometric_stiffening;
    settings.inertia_correction = reduction.inertia_correction;
    settings.planar = reduction.planar;
    settings.stress_shapes = reduction.stress_shapes;
    settings.load_points = reduction.load_points.clone();
    settings.factor = reduction.factor;
    settings
}

/// Shows a stage of the reduction of part `part`; the single-precision refinement is a
/// figure of the run, kept in the log.
fn reduction_stage(part: &str, stage: reduction::Stage, obs: &mut dyn Observer) {
    let what = match stage {
        reduction::Stage::Assembling => "assembling K and M".to_string(),
        reduction::Stage::Factorising { internal_dofs } => format!("factorising K_ii ({internal_dofs} dofs)"),
        reduction::Stage::Factorised {
            factor_len, precision, ..
        } => format!(
            "K_ii factored: {:.1} M values, {:.2} GB in {} precision",
            factor_len as f64 / 1e6,
            (factor_len * precision.bytes()) as f64 / 1e9,
            precision.name()
        ),
        reduction::Stage::ConstraintModes { count } => format!("{count} constraint modes"),
        reduction::Stage::Solved {
            constraint_steps,
            applications,
            factor_solves,
        } if factor_solves > applications => {
            // A figure of the run, not a passing stage: kept in the log (a stage line only
            // shows on a terminal).
            obs.progress(&Progress::Info(format!(
                "part '{}': refined solves with the single-precision factor: {constraint_steps} per constraint mode, {:.2} per Lanczos vector ({applications} vectors)",
                part,
                factor_solves as f64 / applications.max(1) as f64
            )));
            return;
        }
        reduction::Stage::EigenIteration { converged, wanted, .. } => {
            format!("fixed-interface modes: {converged} of {wanted} converged")
        }
        reduction::Stage::Projecting => "projecting K_CB, M_CB".to_string(),
        reduction::Stage::Invariants => "inertia invariants".to_string(),
        _ => return,
    };
    obs.progress(&Progress::Stage(format!("part '{}': {what}", part)));
}

/// Writes the reduced `body` to the cache `file` (in the folder `cache`) with its `key`.
fn save(
    part: &Part,
    body: &ReducedBody,
    cache: &Path,
    file: &Path,
    key: &str,
    obs: &mut dyn Observer,
) -> Result<(), BoxError> {
    std::fs::create_dir_all(cache).context(|| format!("cannot create the cache folder {}", cache.display()))?;
    reduction::file::write(body, file).context(|| format!("part '{}': cannot write the reduced body", part.name))?;
    super::cache::record(file, key).context(|| {
        format!(
            "part '{}': cannot record the cache key of {}",
            part.name,
            file.display()
        )
    })?;
    obs.progress(&Progress::Info(format!(
        "part '{}': saved to the cache as {}",
        part.name,
        file.display()
    )));
    Ok(())
}

/// Reduces (or reads from the cache) every flexible body's part, once per part.
fn reduce_bodies(study: &Study, cache: &Path, obs: &mut dyn Observer) -> Result<ReducedBodies, BoxError> {
    let mut done: BTreeMap<usize, Reduced> = BTreeMap::new();
    let mut out = Vec::new();
    let mut reductions = Vec::new();
    for b in &study.mechanism.bodies {
        match &b.source {
            BodySource::Part(p) => {
                if !done.contains_key(p) {
                    let r = reduce_part(study, &study.parts[*p], cache, obs)?;
                    reductions.push(json!({
                        "part": study.parts[*p].name,
                        "fe_dofs": r.free_dofs,
                        "coordinates": r.body.n_coordinates(),
                        "interfaces": r.body.interfaces.len(),
                        "modes_kept": r.body.n_modes,
                        "from_cache": r.from_cache,
                    }));
                    done.insert(*p, r);
                }
                let r = &done[p];
                let mesh = (r.body.mesh.as_ref().map(|m| m.nodes.len()) == Some(r.built.model.node_count()))
                    .then(|| VtuMesh::from_model(&r.built.model, &[]));
                out.push((Arc::clone(&r.body), mesh));
            }
            BodySource::File(_, body) => out.push((Arc::clone(body), None)),
        }
    }
    Ok((out, reductions))
}

/// The mechanism of `study`, its bodies reduced (or read from the cache in `cache`) first.
pub fn build_mechanism(study: &Study, cache: &Path, obs: &mut dyn Observer) -> Result<BuiltMechanism, BoxError> {
    crate::build::build(study, reduce_bodies(study, cache, obs)?)
}

/// A reduced body copied into the results folder by [`reduce_command`].
#[derive(Clone, Debug)]
pub struct ReducedFile {
    pub part: String,
    pub coordinates: usize,
    pub interfaces: usize,
    pub modes: usize,
    pub path: PathBuf,
}

/// `flexmbs reduce`: reduces every part with a `[parts.reduction]`, or the one named, and
/// copies the bodies into the results folder.
pub fn reduce_command(
    study: &Study,
    only: Option<&str>,
    options: &Options,
    obs: &mut dyn Observer,
) -> Result<Vec<ReducedFile>, BoxError> {
    let parts: Vec<&Part> = match only {
        Some(name) => {
            let part = &study.parts[study.part(name)?];
            if part.reduction.is_none() {
                return Err(format!(
                    "part '{name}' has no [parts.reduction] in {} (parts that do: {})",
                    study.source.path.display(),
                    reducible(study)
                )
                .into());
            }
            vec![part]
        }
        None => study.parts.iter().filter(|p| p.reduction.is_some()).collect(),
    };
    if parts.is_empty() {
        return Err(format!(
            "no part of {} has a [parts.reduction]: nothing to reduce",
            study.source.path.display()
        )
        .into());
    }
    let out = options.results_dir(study);
    if out.as_os_str().is_empty() {
        return Err(
            "the output folder is '' (an empty path): name a folder, e.g. --out bodies, or --out . for the current one"
                .into(),
        );
    }
    std::fs::create_dir_all(&out).context(|| format!("cannot create the results folder {}", out.display()))?;
    let cache = options.cache_dir(study);
    let mut written = Vec::new();
    for part in parts {
        let r = reduce_part(study, part, &cache, obs)?;
        let target = out.join(format!("{}.{}", part.name, reduction::file::EXTENSION));
        std::fs::copy(&r.file, &target)
            .context(|| format!("cannot copy {} to {}", r.file.display(), target.display()))?;
        written.push(ReducedFile {
            part: part.name.clone(),
            coordinates: r.body.n_coordinates(),
            interfaces: r.body.interfaces.len(),
            modes: r.body.n_modes,
            path: target,
        });
    }
    Ok(written)
}

fn reducible(study: &Study) -> String {
    let names: Vec<&str> = study
        .parts
        .iter()
        .filter(|p| p.reduction.is_some())
        .map(|p| p.name.as_str())
        .collect();
    if names.is_empty() {
        "none".into()
    } else {
        names.join(", ")
    }
}
