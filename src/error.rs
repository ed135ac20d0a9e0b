//! One error type for the whole crate, so that an application can `?` every constructor and
//! validating call of `beamfield` into a single `Result<_, beamfield::Error>`.
//!
//! Each public error type of the crate converts into [`Error`] with `From` (and therefore with
//! `?`); the variant keeps the original error, so nothing is lost by converting. Functions keep
//! returning their own precise error types: match on those where the cause matters, convert to
//! [`Error`] where it is only reported.

use crate::correlation::CorrelationError;
use crate::em::EmError;
use crate::field::{BlobError, EdtError, FreeSpaceError, LikelihoodError};
use crate::intrinsics::IntrinsicsError;
use crate::landmark::{IntersectionError, LandmarkError};
use crate::lidar::assembler::AssemblerError;
use crate::lidar::ld06::Ld06Error;
use crate::lidar::rplidar::RplidarError;
use crate::lidar::xv11::Xv11Error;
use crate::lidar::ydlidar::YdlidarError;
use crate::lidar::EncodeError;
use crate::link::LinkError;
use crate::mcl::{MclError, MotionError};
use crate::raycast::RayCastError;
use crate::scan::ScanError;
use crate::sonar::{CrosstalkError, FitError, RingError, ScheduleError};
use crate::tempered::{NormalizeError, TemperError};

/// Any error of the crate. `Display` names the part of the crate and then the original error's
/// message.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum Error {
    /// A distance-field blob was rejected ([`crate::FieldView::parse`], [`crate::emit_blob`]).
    Blob(BlobError),
    /// The distance transform's input or scratch space was rejected ([`crate::squared_edt`]).
    Edt(EdtError),
    /// Likelihood-field parameters were rejected ([`crate::LikelihoodParams`]).
    Likelihood(LikelihoodError),
    /// Beam-model intrinsics were rejected ([`crate::BeamIntrinsics`]).
    Intrinsics(IntrinsicsError),
    /// A scan or a beam layout was rejected ([`crate::Scan`], [`crate::BeamLayout`]).
    Scan(ScanError),
    /// A ray caster could not be built ([`crate::RayCaster::new`]).
    RayCast(RayCastError),
    /// The tempering exponent or stride was rejected ([`crate::Tempered::new`]).
    Temper(TemperError),
    /// Log-weights could not be normalized ([`crate::normalize_log_weights`]).
    Normalize(NormalizeError),
    /// An EM fit was refused ([`crate::em`]).
    Em(EmError),
    /// A map correlation could not be set up ([`crate::MapCorrelation`]).
    Correlation(CorrelationError),
    /// A landmark, feature or noise model was rejected ([`crate::landmark`]).
    Landmark(LandmarkError),
    /// Two features give no pose ([`crate::landmark`]'s two-feature proposal).
    Intersection(IntersectionError),
    /// An ultrasonic ring's geometry was rejected ([`crate::sonar::Ring`]).
    Ring(RingError),
    /// A firing schedule was rejected ([`crate::sonar::Schedule`]).
    Schedule(ScheduleError),
    /// A crosstalk model was rejected ([`crate::sonar::CrosstalkModel`]).
    Crosstalk(CrosstalkError),
    /// A crosstalk probability could not be fitted ([`crate::sonar::fit_constant_q`], [`crate::sonar::fit_gaussian_q`]).
    SonarFit(FitError),
    /// A free-space section was rejected ([`crate::field::FreeSpace`]).
    FreeSpace(FreeSpaceError),
    /// The localizer's configuration or an update was refused ([`crate::mcl`]).
    Mcl(MclError),
    /// An odometry step or its noise was rejected ([`crate::mcl::OdometryStep`]).
    Motion(MotionError),
    /// A LiDAR revolution could not be encoded ([`crate::lidar`]'s encoders).
    LidarEncode(EncodeError),
    /// An LD06 / LD19 frame could not be built ([`crate::lidar::ld06`]).
    Ld06(Ld06Error),
    /// An RPLIDAR command or node could not be built or read ([`crate::lidar::rplidar`]).
    Rplidar(RplidarError),
    /// An XV-11 packet could not be built ([`crate::lidar::xv11`]).
    Xv11(Xv11Error),
    /// A YDLIDAR packet could not be read ([`crate::lidar::ydlidar`]).
    Ydlidar(YdlidarError),
    /// A scan assembler could not be set up ([`crate::lidar::ScanAssembler`]).
    Assembler(AssemblerError),
    /// A frame of the device link was refused or could not be written ([`crate::link`]).
    Link(LinkError),
    /// The fixed-point path was refused ([`crate::fixed_point`]).
    #[cfg(feature = "fixed")]
    Fixed(crate::fixed_point::FixedError),
    /// The ultrasonic ring driver's configuration was rejected (feature `hal`).
    #[cfg(feature = "hal")]
    SonarConfig(crate::sonar::driver::ConfigError),
    /// The ultrasonic ring driver's I²C bus failed (feature `hal`); the bus error's kind.
    #[cfg(feature = "hal")]
    SonarBus(#[cfg_attr(feature = "defmt", defmt(Debug2Format))] embedded_hal::i2c::ErrorKind),
}

impl core::fmt::Display for Error {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Blob(e) => write!(f, "distance-field blob: {e}"),
            Self::Edt(e) => write!(f, "distance transform: {e}"),
            Self::Likelihood(e) => write!(f, "likelihood field: {e}"),
            Self::Intrinsics(e) => write!(f, "beam intrinsics: {e}"),
            Self::Scan(e) => write!(f, "scan: {e}"),
            Self::RayCast(e) => write!(f, "ray caster: {e}"),
            Self::Temper(e) => write!(f, "tempering: {e}"),
            Self::Normalize(e) => write!(f, "weight normalization: {e}"),
            Self::Em(e) => write!(f, "em: {e}"),
            Self::Correlation(e) => write!(f, "map correlation: {e}"),
            Self::Landmark(e) => write!(f, "landmark: {e}"),
            Self::Intersection(e) => write!(f, "two-feature pose: {e}"),
            Self::Ring(e) => write!(f, "sonar ring: {e}"),
            Self::Schedule(e) => write!(f, "sonar schedule: {e}"),
            Self::Crosstalk(e) => write!(f, "sonar crosstalk: {e}"),
            Self::SonarFit(e) => write!(f, "sonar fit: {e}"),
            Self::FreeSpace(e) => write!(f, "free-space section: {e}"),
            Self::Mcl(e) => write!(f, "localizer: {e}"),
            Self::Motion(e) => write!(f, "odometry: {e}"),
            Self::LidarEncode(e) => write!(f, "lidar encoder: {e}"),
            Self::Ld06(e) => write!(f, "ld06: {e}"),
            Self::Rplidar(e) => write!(f, "rplidar: {e}"),
            Self::Xv11(e) => write!(f, "xv11: {e}"),
            Self::Ydlidar(e) => write!(f, "ydlidar: {e}"),
            Self::Assembler(e) => write!(f, "scan assembler: {e}"),
            Self::Link(e) => write!(f, "link: {e}"),
            #[cfg(feature = "fixed")]
            Self::Fixed(e) => write!(f, "fixed point: {e}"),
            #[cfg(feature = "hal")]
            Self::SonarConfig(e) => write!(f, "sonar driver: {e}"),
            #[cfg(feature = "hal")]
            Self::SonarBus(kind) => write!(f, "sonar driver: i2c bus error: {kind}"),
        }
    }
}

impl core::error::Error for Error {
    fn source(&self) -> Option<&(dyn core::error::Error + 'static)> {
        Some(match self {
            Self::Blob(e) => e,
            Self::Edt(e) => e,
            Self::Likelihood(e) => e,
            Self::Intrinsics(e) => e,
            Self::Scan(e) => e,
            Self::RayCast(e) => e,
            Self::Temper(e) => e,
            Self::Normalize(e) => e,
            Self::Em(e) => e,
            Self::Correlation(e) => e,
            Self::Landmark(e) => e,
            Self::Intersection(e) => e,
            Self::Ring(e) => e,
            Self::Schedule(e) => e,
            Self::Crosstalk(e) => e,
            Self::SonarFit(e) => e,
            Self::FreeSpace(e) => e,
            Self::Mcl(e) => e,
            Self::Motion(e) => e,
            Self::LidarEncode(e) => e,
            Self::Ld06(e) => e,
            Self::Rplidar(e) => e,
            Self::Xv11(e) => e,
            Self::Ydlidar(e) => e,
            Self::Assembler(e) => e,
            Self::Link(e) => e,
            #[cfg(feature = "fixed")]
            Self::Fixed(e) => e,
            #[cfg(feature = "hal")]
            Self::SonarConfig(e) => e,
            #[cfg(feature = "hal")]
            Self::SonarBus(_) => return None,
        })
    }
}

/// `From<$ty> for Error`, wrapping in `Error::$variant`.
macro_rules! from_error {
    ($($(#[$cfg:meta])? $ty:ty => $variant:ident),* $(,)?) => {
        $(
            $(#[$cfg])?
            impl From<$ty> for Error {
                fn from(e: $ty) -> Self {
                    Self::$variant(e)
                }
            }
        )*
    };
}

from_error! {
    BlobError => Blob,
    EdtError => Edt,
    LikelihoodError => Likelihood,
    IntrinsicsError => Intrinsics,
    ScanError => Scan,
    RayCastError => RayCast,
    TemperError => Temper,
    NormalizeError => Normalize,
    EmError => Em,
    CorrelationError => Correlation,
    LandmarkError => Landmark,
    IntersectionError => Intersection,
    RingError => Ring,
    ScheduleError => Schedule,
    CrosstalkError => Crosstalk,
    FitError => SonarFit,
    FreeSpaceError => FreeSpace,
    MclError => Mcl,
    MotionError => Motion,
    EncodeError => LidarEncode,
    Ld06Error => Ld06,
    RplidarError => Rplidar,
    Xv11Error => Xv11,
    YdlidarError => Ydlidar,
    AssemblerError => Assembler,
    LinkError => Link,
    #[cfg(feature = "fixed")] crate::fixed_point::FixedError => Fixed,
    #[cfg(feature = "hal")] crate::sonar::driver::ConfigError => SonarConfig,
}

/// A bus error of the ring driver keeps its [`embedded_hal::i2c::ErrorKind`] (the driver's own
/// [`crate::sonar::driver::Error`] keeps the whole bus error).
#[cfg(feature = "hal")]
impl<E: embedded_hal::i2c::Error> From<crate::sonar::driver::Error<E>> for Error {
    fn from(e: crate::sonar::driver::Error<E>) -> Self {
        match e {
            crate::sonar::driver::Error::I2c(bus) => Self::SonarBus(bus.kind()),
        }
    }
}
