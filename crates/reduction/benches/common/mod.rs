//! The generated solid blocks shared by the `craig_bampton` and `ordering` benches.

use fe_model::{add_interface_on_set, box_mesh, solid_model, CellKind, FeModel, IsotropicMaterial, MassKind, NodeId};
use fe_model::{FillOrdering, SpiderKind};

/// Elements (ex, ey, ez) of a named size: dofs ~ 3 (ex+1)(ey+1)(ez+1).
pub fn divisions(size: &str) -> Option<(usize, usize, usize)> {
    Some(match size {
        "3k" => (12, 8, 8),
        "10k" => (17, 13, 13),
        "25k" => (23, 18, 18),
        "50k" => (30, 23, 23),
        "100k" => (38, 29, 29),
        "200k" => (48, 37, 37),
        "600k" => (70, 53, 53),
        _ => return None,
    })
}

/// A steel hex8 block of `divisions` (ex, ey, ez) elements, 2 ex/ez x ey/ez x 1 m (about
/// 2.6 x 1 x 1 m at every named size), so each element is a 2:1:1 brick, 2/ez m along x and
/// 1/ez m across (not a cube), with RBE2 interface nodes on its end faces x = 0 ("root") and
/// x = max ("tip").
pub fn block((ex, ey, ez): (usize, usize, usize)) -> (FeModel, NodeId, NodeId) {
    let mesh = box_mesh(
        CellKind::Hex8,
        [2.0 * ex as f64 / ez as f64, ey as f64 / ez as f64, 1.0],
        [ex, ey, ez],
    )
    .unwrap();
    let steel = IsotropicMaterial::new("steel", 210e9, 0.3, 7850.0).unwrap();
    let mut model = solid_model(mesh, steel, MassKind::Consistent).unwrap();
    let a = add_interface_on_set(&mut model, "root", "x0", None, SpiderKind::Rbe2).unwrap();
    let b = add_interface_on_set(&mut model, "tip", "x1", None, SpiderKind::Rbe2).unwrap();
    (model, a, b)
}

/// `auto`, `amd` or `nd`.
#[allow(dead_code)]
pub fn parse_ordering(s: &str) -> Option<FillOrdering> {
    Some(match s {
        "auto" => FillOrdering::Auto,
        "amd" => FillOrdering::Amd,
        "nd" => FillOrdering::NestedDissection,
        _ => return None,
    })
}
