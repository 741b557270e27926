// The reduced-body file (`reduction::file`): a body reads back bit for bit (with and without
// mesh shapes, with an auxiliary interface, with awkward scalars), every error names the file
// and what is wrong, and no truncation or random change of a file makes the reader panic or
// accept it.

use fe_model::{FeModel, MassKind, NodeId};
use reduction::file::{self, crc32};
use reduction::{reduce, BodyFileProblem, CbSettings, ModeSelection, ReducedBody, ReductionError};
use std::path::{Path, PathBuf};

/// A free steel beam, `n` elements (n even), interfaces at both ends.
fn beam(n: usize) -> (FeModel, Vec<(String, NodeId)>, Vec<NodeId>) {
    let (model, nodes) = super::common::skew_steel_beam(n, super::common::d20(), MassKind::Consistent);
    let interfaces = vec![("A".to_string(), nodes[0]), ("B".to_string(), nodes[n])];
    (model, interfaces, nodes)
}

fn body(n: usize, modes: usize, mesh: bool) -> ReducedBody {
    let (model, interfaces, _) = beam(n);
    let mut settings = CbSettings::new(ModeSelection::Count(modes));
    settings.keep_mesh_shapes = mesh;
    reduce(&model, "beam", &interfaces, &settings).unwrap()
}

/// Every f64 of a body as its bits, in a fixed order: `PartialEq` says 0.0 == -0.0 and
/// NaN != NaN, so identity is checked on the bits.
fn f64_bits(b: &ReducedBody) -> Vec<u64> {
    let mut v: Vec<f64> = Vec::new();
    v.extend(&b.fixed_interface_omega);
    for p in &b.interfaces {
        v.extend(p.position);
    }
    let i = &b.inertia;
    v.push(i.mass);
    v.extend(i.center_of_mass);
    v.extend(i.inertia_com.iter().flatten());
    for m in [&b.K_CB, &b.M_CB, &i.S_t, &i.S_r, &i.S_x, &b.Phi_com]
        .into_iter()
        .chain(i.S_bar.iter())
    {
        v.extend(&m.data);
    }
    if let Some(mesh) = &b.mesh {
        v.extend(mesh.nodes.iter().flatten());
        v.extend(&mesh.shapes.data);
    }
    v.iter().map(|x| x.to_bits()).collect()
}

fn assert_identical(a: &ReducedBody, b: &ReducedBody) {
    assert_eq!(a, b);
    assert_eq!(f64_bits(a), f64_bits(b), "some f64 changed its bits");
}

fn origin() -> PathBuf {
    PathBuf::from("bodies/beam.rbody")
}

/// The problem of a read that must fail, after checking that the error names the file.
fn problem(bytes: &[u8]) -> BodyFileProblem {
    match file::from_bytes(bytes, &origin()) {
        Err(e @ ReductionError::BodyFile { .. }) => {
            assert!(
                e.to_string().contains("bodies/beam.rbody"),
                "the message does not name the file: {e}"
            );
            let ReductionError::BodyFile { path, problem } = e else {
                unreachable!()
            };
            assert_eq!(path, origin());
            problem
        }
        Err(other) => panic!("not a BodyFile error: {other}"),
        Ok(_) => panic!("a damaged file was accepted"),
    }
}

/// The parts of a file: header lines, JSON metadata, array section.
fn parts(bytes: &[u8]) -> (usize, serde_json::Value, usize) {
    let line1 = bytes.iter().position(|&b| b == b'\n').unwrap() + 1;
    let line2 = line1 + bytes[line1..].iter().position(|&b| b == b'\n').unwrap() + 1;
    let header = std::str::from_utf8(&bytes[line1..line2 - 1]).unwrap();
    let len: usize = header.split(' ').nth(1).unwrap().parse().unwrap();
    let json = serde_json::from_slice(&bytes[line2..line2 + len]).unwrap();
    (line2, json, line2 + len + 1)
}

/// The file with its metadata JSON replaced by `json` and a valid checksum for it: a file as
/// a buggy or hostile writer could make it, so the checks behind the checksum are reached.
fn with_metadata(bytes: &[u8], json: &[u8]) -> Vec<u8> {
    let (_, _, binary) = parts(bytes);
    let mut out = format!("{} {}\n", file::MAGIC, reduction::FORMAT_VERSION).into_bytes();
    out.extend(format!("metadata {} crc32 {:08x}\n", json.len(), crc32(json)).as_bytes());
    out.extend(json);
    out.push(b'\n');
    out.extend(&bytes[binary..]);
    out
}

fn edit_metadata(bytes: &[u8], edit: impl FnOnce(&mut serde_json::Value)) -> Vec<u8> {
    let (_, mut json, _) = parts(bytes);
    edit(&mut json);
    with_metadata(bytes, &serde_json::to_vec_pretty(&json).unwrap())
}

#[test]
fn crc32_is_the_standard_one() {
    // The check value of CRC-32/ISO-HDLC (zlib, Python binascii.crc32).
    assert_eq!(crc32(b"123456789"), 0xCBF4_3926);
    assert_eq!(crc32(b""), 0);
}

#[test]
fn round_trip_is_bit_identical_with_modes_and_mesh_shapes() {
    let b = body(8, 4, true);
    assert!(b.mesh.is_some() && b.n_modes == 4);
    let bytes = file::to_bytes(&b, &origin()).unwrap();
    let back = file::from_bytes(&bytes, &origin()).unwrap();
    assert_identical(&b, &back);
    // Written again, the same bytes: nothing depends on anything but the body.
    assert_eq!(file::to_bytes(&back, &origin()).unwrap(), bytes);
    // The header is readable text.
    let text = String::from_utf8_lossy(&bytes[..200]);
    assert!(text.starts_with(&format!("FLEXMBS-RBODY {}\nmetadata ", reduction::FORMAT_VERSION)), "{text}");
}

#[test]
fn round_trip_without_mesh_shapes_and_with_an_auxiliary_interface() {
    let b = body(6, 3, false);
    assert!(b.mesh.is_none());
    assert_identical(
        &b,
        &file::from_bytes(&file::to_bytes(&b, &origin()).unwrap(), &origin()).unwrap(),
    );

    // The middle node of a uniform straight beam is its centre of mass.
    let (model, interfaces, nodes) = beam(6);
    let mut settings = CbSettings::new(ModeSelection::Count(2));
    settings.auxiliary_node = Some(nodes[3]);
    let b = reduce(&model, "beam", &interfaces, &settings).unwrap();
    assert_eq!(b.auxiliary_interface, Some(2));
    assert_identical(
        &b,
        &file::from_bytes(&file::to_bytes(&b, &origin()).unwrap(), &origin()).unwrap(),
    );

    // Static modes only: no modes, empty frequency list.
    let b = reduce(
        &model,
        "static",
        &interfaces,
        &CbSettings::new(ModeSelection::StaticOnly),
    )
    .unwrap();
    assert_identical(
        &b,
        &file::from_bytes(&file::to_bytes(&b, &origin()).unwrap(), &origin()).unwrap(),
    );
}

#[test]
fn awkward_scalars_survive_the_json_bit_for_bit() {
    // The JSON scalars need serde_json's correctly rounded parser (float_roundtrip): these
    // are values where a fast parser can be an ulp off, the extremes, and a negative zero.
    let mut b = body(4, 2, true);
    b.inertia.mass = 0.1 + 0.2;
    b.inertia.center_of_mass = [-0.0, 5e-324, 1.7976931348623157e308];
    b.inertia.inertia_com[0] = [2.2250738585072014e-308, 9007199254740993.0, 1.0 / 3.0];
    b.inertia.inertia_com[1][2] = 8.98846567431158e307;
    b.fixed_interface_omega[0] = std::f64::consts::PI * 1e10;
    b.interfaces[1].position = [f64::MIN_POSITIVE, -f64::EPSILON, 123456789.12345679];
    // Binary arrays hold anything, NaN included.
    b.K_CB.data[3] = f64::NAN;
    b.M_CB.data[5] = f64::NEG_INFINITY;
    // Physically these data are nonsense (the physical checks of `from_bytes` refuse them,
    // `tests/unit/physics.rs`); the format itself must carry them.
    let back = file::from_bytes_unchecked(&file::to_bytes(&b, &origin()).unwrap(), &origin()).unwrap();
    assert_eq!(f64_bits(&b), f64_bits(&back));
}

#[test]
fn write_and_read_a_file_on_disk() {
    let dir = std::env::temp_dir().join(format!("reduction-file-format-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(format!("beam.{}", file::EXTENSION));
    let b = body(4, 2, true);
    file::write(&b, &path).unwrap();
    // Writing again replaces the file (atomically, through a temporary file and a rename).
    file::write(&b, &path).unwrap();
    assert_identical(&b, &file::read(&path).unwrap());
    let leftovers: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(leftovers.len(), 1, "temporary files left behind: {leftovers:?}");
    // A missing file: an I/O error that names it.
    let missing = dir.join("missing.rbody");
    let e = file::read(&missing).unwrap_err();
    assert!(
        matches!(
            &e,
            ReductionError::BodyFile {
                problem: BodyFileProblem::Io { action: "read", .. },
                ..
            }
        ) && e.to_string().contains("missing.rbody"),
        "{e}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn wrong_magic_and_unsupported_versions_are_named() {
    let bytes = file::to_bytes(&body(4, 2, false), &origin()).unwrap();
    // Someone passes the JSON of a body, or an MNF.
    let p = problem(br#"{"format_version": 1, "name": "beam"}"#);
    assert!(
        matches!(&p, BodyFileProblem::WrongMagic { found } if found.starts_with("{\"format")),
        "{p}"
    );
    assert!(p.to_string().contains("not a reduced-body file"), "{p}");
    assert!(matches!(problem(b""), BodyFileProblem::WrongMagic { .. }));

    // A newer file: says which version it is and which this build reads.
    let mut newer = bytes.clone();
    newer[14] = b'4';
    let p = problem(&newer);
    assert_eq!(p, BodyFileProblem::UnsupportedVersion { found: 4, supported: 3 });
    let message = p.to_string();
    assert!(
        message.contains("version 4 is newer") && message.contains("reads versions 1 to 3"),
        "{message}"
    );
    let mut older = bytes.clone();
    older[14] = b'0';
    let p = problem(&older);
    assert!(p.to_string().contains("version 0 is not supported"), "{p}");
    // The version is a canonical whole number: "+1" or "01" are not version 1.
    for bad in [
        &b"FLEXMBS-RBODY +1\n"[..],
        b"FLEXMBS-RBODY 01\n",
        b"FLEXMBS-RBODY one\n",
        b"FLEXMBS-RBODY 1",
    ] {
        let mut changed = bad.to_vec();
        changed.extend(&bytes[16..]);
        let p = problem(&changed);
        assert!(matches!(p, BodyFileProblem::Header { line: 1, .. }), "{p}");
    }
}

#[test]
fn truncations_name_the_block_and_the_bytes() {
    let bytes = file::to_bytes(&body(4, 2, true), &origin()).unwrap();
    let (json_start, json, binary) = parts(&bytes);
    // Inside the metadata.
    let p = problem(&bytes[..json_start + 10]);
    assert!(matches!(p, BodyFileProblem::TruncatedMetadata { found: 10, .. }), "{p}");
    // Inside each array: the message names the array and the bytes expected and found.
    for entry in json["arrays"].as_array().unwrap() {
        let (name, offset, size) = (
            entry["name"].as_str().unwrap(),
            entry["offset"].as_u64().unwrap(),
            entry["bytes"].as_u64().unwrap(),
        );
        let cut = binary + offset as usize + size as usize / 2 + 3;
        let p = problem(&bytes[..cut]);
        assert_eq!(
            p,
            BodyFileProblem::TruncatedArray {
                array: name.to_string(),
                offset,
                expected: size,
                found: size / 2 + 3
            }
        );
        assert!(p.to_string().contains(name), "{p}");
    }
    // One byte too many.
    let mut longer = bytes.clone();
    longer.push(0);
    assert!(matches!(
        problem(&longer),
        BodyFileProblem::TrailingBytes { count: 1, .. }
    ));
}

#[test]
fn checksum_mismatches_name_the_block() {
    let bytes = file::to_bytes(&body(4, 2, true), &origin()).unwrap();
    let (json_start, json, binary) = parts(&bytes);
    // A digit of a frequency in the JSON changed: still valid JSON, caught by the checksum.
    let text = String::from_utf8(bytes[json_start..binary - 1].to_vec()).unwrap();
    let at = json_start + text.find("\"mass\": ").unwrap() + 9;
    let mut changed = bytes.clone();
    changed[at] = if changed[at] == b'1' { b'2' } else { b'1' };
    let p = problem(&changed);
    assert!(
        matches!(&p, BodyFileProblem::Checksum { block, .. } if block == "metadata"),
        "{p}"
    );
    // One bit of M_CB.
    let m_cb = &json["arrays"][1];
    assert_eq!(m_cb["name"], "M_CB");
    let mut changed = bytes.clone();
    changed[binary + m_cb["offset"].as_u64().unwrap() as usize + 17] ^= 0x10;
    let p = problem(&changed);
    assert!(
        matches!(&p, BodyFileProblem::Checksum { block, .. } if block == "M_CB"),
        "{p}"
    );
    assert!(
        p.to_string().contains("M_CB") && p.to_string().contains("damaged"),
        "{p}"
    );
}

#[test]
fn malformed_metadata_json_gives_line_and_column() {
    let bytes = file::to_bytes(&body(4, 2, false), &origin()).unwrap();
    // A missing comma on line 3 of the JSON block, behind a valid checksum.
    let json = b"{\n  \"format_version\": 1,\n  \"name\": \"beam\"\n  \"n_modes\": 2\n}";
    let p = problem(&with_metadata(&bytes, json));
    assert!(matches!(p, BodyFileProblem::Json { line: 4, column: 3, .. }), "{p}");
    assert!(p.to_string().contains("file line 6"), "{p}");
    // An unknown field: a v1 file has exactly the v1 fields.
    let p = problem(&edit_metadata(&bytes, |j| j["colour"] = "red".into()));
    assert!(
        matches!(&p, BodyFileProblem::Json { message, .. } if message.contains("colour")),
        "{p}"
    );
}

#[test]
fn inconsistent_shapes_are_refused_with_the_rule() {
    let bytes = file::to_bytes(&body(4, 2, true), &origin()).unwrap();
    // K_CB not n x n with n = 6N + m = 14.
    let p = problem(&edit_metadata(&bytes, |j| j["arrays"][0]["rows"] = 13.into()));
    let message = p.to_string();
    assert!(matches!(p, BodyFileProblem::Shape { .. }), "{p}");
    assert!(
        message.contains("K_CB is 13 x 14 but must be n x n with n = 6N + m"),
        "{message}"
    );
    // n_modes that disagrees with the frequencies.
    let p = problem(&edit_metadata(&bytes, |j| j["n_modes"] = 3.into()));
    assert!(
        p.to_string().contains("2 fixed-interface frequencies for n_modes = 3"),
        "{p}"
    );
    // An interface more: every array would have to be larger.
    let p = problem(&edit_metadata(&bytes, |j| {
        let extra = j["interfaces"][0].clone();
        j["interfaces"].as_array_mut().unwrap().push(extra);
    }));
    assert!(
        p.to_string()
            .contains("K_CB is 14 x 14 but must be n x n with n = 6N + m (N interfaces, m modes) = 20 x 20"),
        "{p}"
    );
    // Arrays swapped in the index.
    let p = problem(&edit_metadata(&bytes, |j| {
        j["arrays"].as_array_mut().unwrap().swap(2, 3)
    }));
    assert!(
        p.to_string()
            .contains("array 2 of the index is 'S_r' where 'S_t' belongs"),
        "{p}"
    );
    // A wrong offset, a missing array, an auxiliary interface that does not exist, absurd counts.
    let p = problem(&edit_metadata(&bytes, |j| j["arrays"][4]["offset"] = 8.into()));
    assert!(p.to_string().contains("S_x is at offset 8"), "{p}");
    let p = problem(&edit_metadata(&bytes, |j| {
        j["arrays"].as_array_mut().unwrap().pop();
    }));
    assert!(p.to_string().contains("the index lists 16 arrays"), "{p}");
    let p = problem(&edit_metadata(&bytes, |j| j["auxiliary_interface"] = 5.into()));
    assert!(
        p.to_string()
            .contains("auxiliary_interface = 5 but there are 2 interfaces"),
        "{p}"
    );
    let p = problem(&edit_metadata(&bytes, |j| j["mesh_nodes"] = (u64::MAX / 2).into()));
    assert!(p.to_string().contains("overflows"), "{p}");
}

#[test]
fn bodies_that_cannot_be_written_are_refused() {
    let mut b = body(4, 2, false);
    b.inertia.mass = f64::NAN;
    let e = file::to_bytes(&b, Path::new("out/nan.rbody")).unwrap_err();
    assert!(
        e.to_string().contains("out/nan.rbody") && e.to_string().contains("mass is NaN"),
        "{e}"
    );
    let mut b = body(4, 2, false);
    b.K_CB.nrows -= 1;
    let e = file::to_bytes(&b, Path::new("out/bad.rbody")).unwrap_err();
    assert!(e.to_string().contains("K_CB is 13 x 14 but must be n x n"), "{e}");
    let mut b = body(4, 2, false);
    b.n_modes = 3;
    assert!(file::to_bytes(&b, Path::new("x"))
        .unwrap_err()
        .to_string()
        .contains("2 frequencies for 3 modes"));
}

// xorshift64* with a fixed seed (`fe_model::fuzz::Mutator`), so that a failure can be replayed.
use fe_model::fuzz::Mutator as Rng;

#[test]
fn no_truncation_or_byte_change_panics_or_is_accepted() {
    let bytes = file::to_bytes(&body(2, 1, true), &origin()).unwrap();
    println!("file of {} bytes", bytes.len());
    // Every truncation.
    for len in 0..bytes.len() {
        problem(&bytes[..len]);
    }
    // Random changes of 1 to 3 bytes, each to a different value, anywhere: all refused (the
    // checksums cover every byte after line 2, and lines 1 and 2 are canonical text).
    let mut rng = Rng::new(0x5EED_F11E);
    let mut kinds = std::collections::BTreeMap::<String, usize>::new();
    for _ in 0..4000 {
        let mut changed = bytes.clone();
        for _ in 0..1 + rng.below(3) {
            let at = rng.below(changed.len());
            changed[at] ^= 1 + rng.below(255) as u8;
        }
        if changed == bytes {
            continue;
        }
        let p = problem(&changed);
        let kind = format!("{p:?}");
        *kinds
            .entry(kind[..kind.find([' ', '{']).unwrap_or(kind.len())].to_string())
            .or_default() += 1;
    }
    // Changes focused on the two header lines, where the checksums do not reach.
    let header_end = parts(&bytes).0;
    for _ in 0..2000 {
        let mut changed = bytes.clone();
        let at = rng.below(header_end);
        changed[at] ^= 1 + rng.below(255) as u8;
        let p = problem(&changed);
        let kind = format!("{p:?}");
        *kinds
            .entry(kind[..kind.find([' ', '{']).unwrap_or(kind.len())].to_string())
            .or_default() += 1;
    }
    println!("problems found: {kinds:?}");
}

#[test]
fn interface_node_labels_are_optional_in_the_file() {
    // A body without labels: no `node_label` key, so its bytes are those of a writer that
    // never knew labels.
    let plain = body(4, 2, false);
    let plain_bytes = file::to_bytes(&plain, &origin()).unwrap();
    let (_, json, _) = parts(&plain_bytes);
    for i in json["interfaces"].as_array().unwrap() {
        let keys: Vec<&String> = i.as_object().unwrap().keys().collect();
        assert_eq!(keys, ["name", "node", "position"]);
    }
    // Labels round-trip; dropping them again gives the same bytes as before.
    let mut labelled = plain.clone();
    labelled.interfaces[0].node_label = Some(1001);
    let bytes = file::to_bytes(&labelled, &origin()).unwrap();
    assert_ne!(bytes, plain_bytes);
    let back = file::from_bytes(&bytes, &origin()).unwrap();
    assert_eq!(back.interfaces[0].node_label, Some(1001));
    assert_eq!(back.interfaces[1].node_label, None);
    assert_eq!(file::to_bytes(&back, &origin()).unwrap(), bytes);
    labelled.interfaces[0].node_label = None;
    assert_eq!(file::to_bytes(&labelled, &origin()).unwrap(), plain_bytes);
    // A file written before labels existed reads, without labels.
    let v1 = file::read(&Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/cantilever_v1.rbody")).unwrap();
    assert!(v1.interfaces.iter().all(|i| i.node_label.is_none()));
}
