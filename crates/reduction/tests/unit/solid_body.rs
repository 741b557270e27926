// From a gmsh file to a reduced body: a hex20 mesh read from MSH 4.1, its "body" volume
// group given a material, RBE2 and RBE3 interfaces on its "clamp" and "tip" face groups,
// and a Craig-Bampton reduction whose interface statics equal the full model's.

use fe_model::mesh::gmsh;
use fe_model::{
    add_interface_on_set, solid_model_with_materials, solve_static, DofMask, IsotropicMaterial, MassKind, NodalLoad,
    SpiderKind,
};
use nalgebra::{DMatrix, DVector, Vector3};
use reduction::{reduce, CbSettings, ModeSelection};
use std::path::Path;

fn fixture(name: &str) -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../fe-model/tests/data/gmsh")
        .join(name)
}

#[test]
fn gmsh_solid_to_reduced_body_keeps_interface_statics() {
    for file in ["hex20_41.msh", "tet10_22_bin.msh"] {
        let mesh = gmsh::read(&fixture(file)).unwrap();
        let steel = IsotropicMaterial::new("steel", 210e9, 0.3, 7850.0).unwrap();
        let mut model = solid_model_with_materials(mesh, &[("body", steel)], MassKind::Consistent).unwrap();
        let clamp = add_interface_on_set(&mut model, "clamp", "clamp", None, SpiderKind::Rbe2).unwrap();
        let tip = add_interface_on_set(&mut model, "tip", "tip", None, SpiderKind::Rbe3).unwrap();
        let interfaces = vec![("clamp".to_string(), clamp), ("tip".to_string(), tip)];
        let body = reduce(&model, "bar", &interfaces, &CbSettings::new(ModeSelection::Count(4))).unwrap();
        // 1 x 0.2 x 0.2 m steel: 314 kg.
        assert!(
            (body.inertia.mass - 7850.0 * 0.04).abs() < 1e-9 * body.inertia.mass,
            "{file}: mass {}",
            body.inertia.mass
        );
        // Clamp the clamp interface, load the tip interface: reduced statics (static modes
        // are exact for interface loads) against the full FE model with the same spiders.
        let n = body.n_coordinates();
        let K = DMatrix::from_fn(n, n, |i, j| body.K_CB.get(i, j));
        let (F, Mo) = (Vector3::new(1e5, -2e5, 3e5), Vector3::new(1e4, 2e3, -5e3));
        let mut f = DVector::zeros(n - 6);
        f.fixed_rows_mut::<3>(0).copy_from(&F);
        f.fixed_rows_mut::<3>(3).copy_from(&Mo);
        let q = K
            .view((6, 6), (n - 6, n - 6))
            .into_owned()
            .cholesky()
            .expect("clamped reduced K is SPD")
            .solve(&f);
        let mut full = model.clone();
        full.add_support(clamp, DofMask::ALL);
        let u = solve_static(
            &full,
            &[NodalLoad {
                node: tip,
                force: F,
                moment: Mo,
            }],
        )
        .unwrap()
        .displacements[tip.index()];
        for k in 0..6 {
            // Round-off of two Cholesky solves of a stiff solid model (cond ~ 1e8).
            assert!(
                (q[k] - u[k]).abs() <= 1e-8 * q.rows(0, 6).amax(),
                "{file} dof {k}: {} vs {}",
                q[k],
                u[k]
            );
        }
    }
}
