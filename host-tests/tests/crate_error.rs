//! `beamfield::Error`: every public error type of the crate converts into it with `?`, the
//! variant keeps the original error, `Display` adds a lower-case prefix to the original message,
//! and `source()` gives the original back.
//!
//! Where a public call fails cheaply, the error is the one that call returns; the other errors
//! are built from their variants.

use beamfield::em::EmError;
use beamfield::fixed_point::FixedError;
use beamfield::landmark::{two_feature_poses, Feature, Landmark};
use beamfield::sonar::driver::{ConfigError, Error as DriverError};
use beamfield::sonar::{fit_constant_q, CrosstalkError, RingError, ScheduleError};
use beamfield::{
    normalize_log_weights, BeamIntrinsics, BeamLayout, CorrelationError, EdtError, Error,
    FieldView, IntersectionError, LikelihoodParams, RayCastError, Scan, SensorMount, Tempered,
};
use core::error::Error as _;
use embedded_hal::i2c::ErrorKind;

/// Converts `e` with `?`, as an application would.
fn via_question_mark<E>(e: E) -> Error
where
    Error: From<E>,
{
    fn fails<E>(e: E) -> Result<(), Error>
    where
        Error: From<E>,
    {
        Err(e)?;
        Ok(())
    }
    match fails(e) {
        Err(got) => got,
        Ok(()) => unreachable!("fails() always returns Err"),
    }
}

/// The converted error shows `prefix: <original message>` and its source is the original.
fn check_wrapped<E: core::error::Error + Copy>(e: E, prefix: &str) -> Error
where
    Error: From<E>,
{
    let got = via_question_mark(e);
    assert_eq!(got.to_string(), format!("{prefix}: {e}"));
    let source = got.source().expect("a wrapped error has a source");
    assert_eq!(source.to_string(), e.to_string());
    got
}

#[test]
fn errors_returned_by_constructors_convert() {
    let blob = FieldView::parse(&[]).expect_err("an empty blob is rejected");
    assert_eq!(
        check_wrapped(blob, "distance-field blob"),
        Error::Blob(blob)
    );

    let scan = Scan::<4>::from_ranges(&[1.0; 5]).expect_err("five ranges in a 4-beam scan");
    assert_eq!(check_wrapped(scan, "scan"), Error::Scan(scan));

    let layout = BeamLayout::<4>::uniform(0.0, 0.1, 4, -1.0, SensorMount::CENTERED)
        .expect_err("a negative max range is rejected");
    assert_eq!(check_wrapped(layout, "scan"), Error::Scan(layout));

    let lf = LikelihoodParams::amcl_defaults(-1.0).expect_err("a negative max range");
    assert_eq!(check_wrapped(lf, "likelihood field"), Error::Likelihood(lf));

    let intr = BeamIntrinsics::amcl_defaults(f32::NAN).expect_err("a NaN max range");
    assert_eq!(
        check_wrapped(intr, "beam intrinsics"),
        Error::Intrinsics(intr)
    );

    let temper = Tempered::new((), 0.0, 1).expect_err("κ = 0 is rejected");
    assert_eq!(check_wrapped(temper, "tempering"), Error::Temper(temper));

    let norm = normalize_log_weights(&mut []).expect_err("no weights");
    assert_eq!(
        check_wrapped(norm, "weight normalization"),
        Error::Normalize(norm)
    );

    let fit = fit_constant_q(&[]).expect_err("no groups");
    assert_eq!(check_wrapped(fit, "sonar fit"), Error::SonarFit(fit));

    let f = Feature::new(1.0, 0.0, 0.0).expect("a valid feature");
    let l = Landmark::new(0.0, 0.0, 0.0).expect("a valid landmark");
    let same = two_feature_poses(&f, &l, &f, &l).expect_err("the same circle twice");
    assert_eq!(
        check_wrapped(same, "two-feature pose"),
        Error::Intersection(same)
    );

    let lm = Feature::new(-1.0, 0.0, 0.0).expect_err("a negative range");
    assert_eq!(check_wrapped(lm, "landmark"), Error::Landmark(lm));
}

#[test]
fn every_other_error_type_converts() {
    let e = EdtError::ScratchTooSmall;
    assert_eq!(check_wrapped(e, "distance transform"), Error::Edt(e));
    let e = RayCastError::StepTooCoarse;
    assert_eq!(check_wrapped(e, "ray caster"), Error::RayCast(e));
    let e = EmError::BadTolerance;
    assert_eq!(check_wrapped(e, "em"), Error::Em(e));
    let e = CorrelationError::EmptyWindow;
    assert_eq!(check_wrapped(e, "map correlation"), Error::Correlation(e));
    let e = RingError::Empty;
    assert_eq!(check_wrapped(e, "sonar ring"), Error::Ring(e));
    let e = ScheduleError::NoGroups;
    assert_eq!(check_wrapped(e, "sonar schedule"), Error::Schedule(e));
    let e = CrosstalkError::BadProbability;
    assert_eq!(check_wrapped(e, "sonar crosstalk"), Error::Crosstalk(e));
    let e = IntersectionError::Concentric;
    assert_eq!(check_wrapped(e, "two-feature pose"), Error::Intersection(e));
    let e = FixedError::MapTooLarge;
    assert_eq!(check_wrapped(e, "fixed point"), Error::Fixed(e));
    let e = ConfigError::BadAddress(0x03);
    assert_eq!(check_wrapped(e, "sonar driver"), Error::SonarConfig(e));
    let e = beamfield::field::FreeSpace::parse(&[]).expect_err("an empty section");
    assert_eq!(check_wrapped(e, "free-space section"), Error::FreeSpace(e));
    let e = beamfield::mcl::MclError::ZeroParticles;
    assert_eq!(check_wrapped(e, "localizer"), Error::Mcl(e));
    let e = beamfield::mcl::MotionError::NonFiniteOdometry;
    assert_eq!(check_wrapped(e, "odometry"), Error::Motion(e));
    let e = beamfield::mcl::odometry::DiffDrive::new(
        beamfield::mcl::odometry::DiffDriveGeometry::new(0.05, 0.05, 0.0, 4096, 0.5),
    )
    .expect_err("a zero wheelbase");
    assert_eq!(check_wrapped(e, "odometry"), Error::Motion(e));
    let e = beamfield::link::decode(&[0x55; 10]).expect_err("garbage");
    assert_eq!(check_wrapped(e, "link"), Error::Link(e));
    let e = beamfield::lidar::EncodeError::BadSampleCount(7);
    assert_eq!(check_wrapped(e, "lidar encoder"), Error::LidarEncode(e));
    let e = beamfield::lidar::ld06::Ld06Error::BadHeader;
    assert_eq!(check_wrapped(e, "ld06"), Error::Ld06(e));
    let e = beamfield::lidar::assembler::AssemblerError::MoreThanOneTurn;
    assert_eq!(check_wrapped(e, "scan assembler"), Error::Assembler(e));
    let e = beamfield::lidar::rplidar::RplidarError::BadCheckBit;
    assert_eq!(check_wrapped(e, "rplidar"), Error::Rplidar(e));
    let e = beamfield::lidar::xv11::Xv11Error::BadStart;
    assert_eq!(check_wrapped(e, "xv11"), Error::Xv11(e));
}

#[test]
fn a_rejected_ydlidar_packet_converts() {
    use beamfield::lidar::ydlidar::{YdlidarError, YdlidarPacket};
    // The YDLidar-SDK protocol document's zero packet with its check code's low byte changed.
    let bad = [
        0xAA, 0x55, 0x01, 0x01, 0x53, 0xAE, 0x53, 0xAE, 0xAC, 0x54, 0x00, 0x00,
    ];
    let e = YdlidarPacket::parse(&bad).expect_err("a wrong check code");
    assert_eq!(
        e,
        YdlidarError::BadChecksum {
            carried: 0x54AC,
            computed: 0x54AB
        }
    );
    assert_eq!(check_wrapped(e, "ydlidar"), Error::Ydlidar(e));
}

/// The ring driver's bus error keeps its `ErrorKind`; it has no `source` (the bus error itself is
/// generic and not stored).
#[test]
fn the_driver_bus_error_keeps_its_kind() {
    let got = via_question_mark(DriverError::I2c(ErrorKind::Bus));
    assert_eq!(got, Error::SonarBus(ErrorKind::Bus));
    assert_eq!(
        got.to_string(),
        format!("sonar driver: i2c bus error: {}", ErrorKind::Bus)
    );
    assert!(got.source().is_none());
}

/// Errors nested inside another error type keep the outer type's variant.
#[test]
fn a_nested_error_keeps_its_outer_type() {
    let inner = BeamIntrinsics::amcl_defaults(-1.0).expect_err("a negative max range");
    let e = EmError::Intrinsics(inner);
    assert_eq!(check_wrapped(e, "em"), Error::Em(e));
}
