//! Fixtures shared by the unit tests.

use fe_model::{FeModel, NodeId};
use nalgebra::{Point3, Vector3};
use reduction::{ModeSelection, ReducedBody};
use std::sync::OnceLock;
use superelement::testing::fixtures;
use superelement::{Damping, FrameChoice, MassVariant, Superelement};

pub struct Fixture {
    pub name: &'static str,
    pub model: FeModel,
    pub interfaces: Vec<NodeId>,
    pub body: ReducedBody,
}

/// A skew straight beam, 4 elements, static modes only.
pub fn beam_static() -> &'static Fixture {
    static F: OnceLock<Fixture> = OnceLock::new();
    F.get_or_init(|| {
        let (model, interfaces, body) = fixtures::straight_beam(
            Point3::new(0.1, -0.2, 0.05),
            Point3::new(1.0, 0.3, 0.45),
            4,
            ModeSelection::StaticOnly,
            false,
        );
        Fixture {
            name: "beam-static",
            model,
            interfaces,
            body,
        }
    })
}

/// The same beam with 8 elements and 4 fixed-interface modes.
pub fn beam_dynamic() -> &'static Fixture {
    static F: OnceLock<Fixture> = OnceLock::new();
    F.get_or_init(|| {
        let (model, interfaces, body) = fixtures::straight_beam(
            Point3::new(0.1, -0.2, 0.05),
            Point3::new(1.0, 0.3, 0.45),
            8,
            ModeSelection::Count(4),
            false,
        );
        Fixture {
            name: "beam-dynamic",
            model,
            interfaces,
            body,
        }
    })
}

/// The beam with an auxiliary interface at its middle node (the centre of mass), 2 modes.
pub fn beam_auxiliary() -> &'static Fixture {
    static F: OnceLock<Fixture> = OnceLock::new();
    F.get_or_init(|| {
        let (model, interfaces, body) = fixtures::straight_beam(
            Point3::new(0.1, -0.2, 0.05),
            Point3::new(1.0, 0.3, 0.45),
            6,
            ModeSelection::Count(2),
            true,
        );
        Fixture {
            name: "beam-auxiliary",
            model,
            interfaces,
            body,
        }
    })
}

/// The L-shaped 3D frame with three interfaces and 3 modes.
pub fn l_frame() -> &'static Fixture {
    static F: OnceLock<Fixture> = OnceLock::new();
    F.get_or_init(|| {
        let (model, interfaces, body) = fixtures::l_frame(ModeSelection::Count(3));
        Fixture {
            name: "l-frame",
            model,
            interfaces,
            body,
        }
    })
}

/// A hex8 block with an RBE2 and an RBE3 interface and 2 modes.
pub fn solid_block() -> &'static Fixture {
    static F: OnceLock<Fixture> = OnceLock::new();
    F.get_or_init(|| {
        let (model, interfaces, body) = fixtures::solid_block(ModeSelection::Count(2));
        Fixture {
            name: "solid-block",
            model,
            interfaces,
            body,
        }
    })
}

pub fn all_fixtures() -> Vec<&'static Fixture> {
    vec![
        beam_static(),
        beam_dynamic(),
        beam_auxiliary(),
        l_frame(),
        solid_block(),
    ]
}

/// Every frame choice that fits `body`.
pub fn frame_choices(body: &ReducedBody) -> Vec<FrameChoice> {
    let N = body.interfaces.len();
    let mut v = vec![
        FrameChoice::CenterOfMass,
        FrameChoice::InterfaceNode(0),
        FrameChoice::InterfaceNode(N - 1),
    ];
    if body.auxiliary_interface.is_some() {
        v.push(FrameChoice::AuxiliaryNode);
    }
    v
}

pub fn superelement(body: &ReducedBody, frame: FrameChoice, mass: MassVariant) -> Superelement {
    Superelement::new(body, frame, mass, Damping::none()).unwrap()
}

pub const VARIANTS: [MassVariant; 2] = [MassVariant::Exact, MassVariant::Lumped];

pub fn gravity() -> Vector3<f64> {
    Vector3::new(0.5, -9.81, 1.3)
}

/// Resultant force and moment about the origin of interface forces `f` (6 entries per
/// interface: force, then moment) applied at the interface positions `r`.
pub fn resultant(f: &[f64], r: &[Vector3<f64>]) -> (Vector3<f64>, Vector3<f64>) {
    let (mut F, mut Mo) = (Vector3::zeros(), Vector3::zeros());
    for (k, r_k) in r.iter().enumerate() {
        let force = Vector3::new(f[6 * k], f[6 * k + 1], f[6 * k + 2]);
        let moment = Vector3::new(f[6 * k + 3], f[6 * k + 4], f[6 * k + 5]);
        F += force;
        Mo += moment + r_k.cross(&force);
    }
    (F, Mo)
}

/// `state` placed rigidly by rotation `Q` then translation `t` (interfaces and the frame's
/// warm start `frame` alike), for invariance checks.
pub fn rigidly_moved(
    state: &superelement::BodyState,
    frame: &superelement::Frame,
    Q: &nalgebra::UnitQuaternion<f64>,
    t: &Vector3<f64>,
) -> superelement::BodyState {
    let mut moved = state.clone();
    for k in 0..state.r.len() {
        moved.r[k] = t + Q * state.r[k];
        moved.R[k] = Q * state.R[k];
    }
    moved.frame = superelement::Frame::new(t + Q * frame.r, Q * frame.R);
    moved
}
