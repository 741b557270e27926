use mbs::{CoordinateQuantity, JointKind};
use nalgebra::Vector3;

/// Every scalar coordinate of every joint kind, in the order of `JointKind`'s docs.
#[test]
fn joint_coordinate_quantities_follow_the_joint_docs() {
    use CoordinateQuantity::{Angle, Length};
    let a = Vector3::z();
    let cases = [
        (JointKind::Revolute { axis: a }, vec![Angle]),
        (JointKind::Prismatic { axis: a }, vec![Length]),
        (JointKind::Cylindrical { axis: a }, vec![Length, Angle]),
        (
            JointKind::Universal {
                axis1: a,
                axis2: Vector3::x(),
            },
            vec![Angle, Angle],
        ),
        (JointKind::Planar { normal: a }, vec![Length, Length, Angle]),
    ];
    for (kind, expected) in cases {
        assert_eq!(kind.n_scalar(), expected.len(), "{}", kind.name());
        let got: Vec<_> = (0..kind.n_scalar()).map(|c| kind.coordinate_quantity(c)).collect();
        assert_eq!(got, expected, "{}", kind.name());
    }
    assert_eq!(Angle.unit(), "rad");
    assert_eq!(Angle.rate_unit(), "rad/s");
    assert_eq!(Length.rate_unit(), "m/s");
    assert_eq!(Angle.effort_unit(), "N m");
    assert_eq!(Length.effort_unit(), "N");
}
