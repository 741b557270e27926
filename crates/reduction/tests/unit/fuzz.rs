// Fuzzing of the reduced-body and Matrix Market readers with the shared seeded mutator
// (`fe_model::fuzz`): a fixed number of mutants per run, none may panic. Reduced-body mutants
// of the metadata get a recomputed checksum, so they reach the JSON, shape and physics checks
// instead of stopping at the checksum.

use fe_model::fuzz::{budget, Mutator};
use reduction::file;
use std::path::Path;

fn free_body() -> reduction::ReducedBody {
    use super::common::{beam_model, d20, steel};
    use fe_model::{BeamTheory, MassKind};
    use nalgebra::{Point3, Vector3};
    let (model, nodes) = beam_model(
        steel(),
        d20(),
        (BeamTheory::Timoshenko, MassKind::Consistent),
        Vector3::y(),
        (Point3::origin(), Point3::new(1.0, 0.0, 0.0)),
        4,
    );
    let interfaces = vec![("A".to_string(), nodes[0]), ("B".to_string(), nodes[4])];
    let mut settings = reduction::CbSettings::new(reduction::ModeSelection::Count(2));
    settings.keep_mesh_shapes = true;
    reduction::reduce(&model, "fuzz", &interfaces, &settings).unwrap()
}

/// Parses `bytes` as a reduced body; a panic fails the test with the case.
fn no_panic(bytes: &[u8], case: usize) {
    let r = std::panic::catch_unwind(|| file::from_bytes(bytes, Path::new("fuzz.rbody")).map_err(|e| e.to_string()));
    assert!(r.is_ok(), "reduced-body reader panicked on mutant {case}");
}

#[test]
fn reduced_body_mutants_never_panic() {
    let bytes = file::to_bytes(&free_body(), Path::new("fuzz.rbody")).unwrap();
    // Split: line 1, line 2 (`metadata <len> crc32 <hex>`), the JSON, the arrays.
    let l1 = bytes.iter().position(|&b| b == b'\n').unwrap() + 1;
    let l2 = l1 + bytes[l1..].iter().position(|&b| b == b'\n').unwrap() + 1;
    let line2 = std::str::from_utf8(&bytes[l1..l2]).unwrap();
    let json_len: usize = line2.split(' ').nth(1).unwrap().parse().unwrap();
    let json = &bytes[l2..l2 + json_len];
    let arrays = &bytes[l2 + json_len + 1..];
    let mut m = Mutator::new(0x7262_6f64_7966_7a01);
    for case in 0..budget(1500) {
        // Whole-file mutants (mostly checksum errors) and metadata mutants with a valid checksum.
        let mutant = if case % 3 == 0 {
            m.mutate(&bytes)
        } else {
            let j = m.mutate(json);
            let mut out = bytes[..l1].to_vec();
            out.extend_from_slice(format!("metadata {} crc32 {:08x}\n", j.len(), file::crc32(&j)).as_bytes());
            out.extend_from_slice(&j);
            out.push(b'\n');
            out.extend_from_slice(arrays);
            out
        };
        no_panic(&mutant, case);
    }
}

#[test]
fn matrix_market_mutants_never_panic() {
    let texts: Vec<Vec<u8>> = vec![
        b"%%MatrixMarket matrix coordinate real symmetric\n% K\n4 4 7\n1 1 2.0\n2 1 -1.0\n2 2 3.0\n3 2 -1.0\n3 3 4.0\n4 3 -1.0\n4 4 5.0\n".to_vec(),
        b"%%MatrixMarket matrix coordinate real general\n4 4 4\n1 1 1e3\n2 2 1e3\n3 3 1e3\n4 4 1e3\n".to_vec(),
    ];
    let mut m = Mutator::new(0x6d6d_6675_7a7a_0001);
    for (t, text) in texts.iter().enumerate() {
        // The original reads.
        reduction::matrix_market::parse_matrix_market(text, Path::new("k.mtx")).unwrap();
        for case in 0..budget(1500) {
            let mutant = m.mutate(text);
            let r = std::panic::catch_unwind(|| {
                reduction::matrix_market::parse_matrix_market(&mutant, Path::new("k.mtx")).map_err(|e| e.to_string())
            });
            assert!(r.is_ok(), "Matrix Market reader panicked on text {t}, mutant {case}: {:?}", String::from_utf8_lossy(&mutant));
        }
    }
}
