//! The SRF08 ring driver (feature `hal`) against embedded-hal-mock: the exact I²C transactions
//! of one schedule cycle, the delays between groups, co-fired tags, and errors.

use beamfield::sonar::driver::{ConfigError, Error, RingScan, SonarRing};
use beamfield::sonar::{Ring, Schedule};
use embedded_hal::i2c::ErrorKind;
use embedded_hal_mock::eh1::delay::{CheckedDelay, Transaction as D};
use embedded_hal_mock::eh1::i2c::{Mock as I2cMock, Transaction as I};

fn ring() -> Ring<6> {
    Ring::uniform(6, 0.0, -60f32.to_radians(), 0.2, 0.3, 5.0).unwrap()
}

const ADDR: [u8; 6] = [0x70, 0x71, 0x72, 0x73, 0x74, 0x75];

fn start(a: u8) -> I {
    I::write(a, vec![0x00, 0x51])
}

fn read(a: u8, cm: u16) -> I {
    I::write_read(a, vec![0x02], cm.to_be_bytes().to_vec())
}

#[test]
fn one_cycle_of_opposite_pairs() {
    // Opposite pairs, 70 ms apart (longer than the 29.2 ms echo lifetime of 5 m).
    let sched = Schedule::<6, 3>::new(&ring(), &[&[0, 3], &[1, 4], &[2, 5]], 0.07, 343.0).unwrap();
    let expect = [
        start(0x70),
        start(0x73),
        read(0x70, 123),
        read(0x73, 0),
        start(0x71),
        start(0x74),
        read(0x71, 300),
        read(0x74, 45),
        start(0x72),
        start(0x75),
        read(0x72, 499),
        read(0x75, 0x0102),
    ];
    let i2c = I2cMock::new(&expect);
    let delay = CheckedDelay::new(&[
        D::delay_us(70_000),
        D::delay_us(70_000),
        D::delay_us(70_000),
    ]);
    let mut ring = SonarRing::new(i2c, delay, &ADDR, sched)
        .map_err(|e| e.0)
        .unwrap();
    let mut out = RingScan::<6>::default();
    ring.read_cycle(&mut out).unwrap();
    let want = [1.23, 3.0, 4.99, f32::INFINITY, 0.45, 2.58];
    for (k, (&got, &w)) in out.scan.ranges_m().iter().zip(&want).enumerate() {
        assert!(
            got == w || (got - w).abs() < 1e-6,
            "transducer {k}: {got} vs {w}"
        );
    }
    assert_eq!(out.cofired.as_slice(), &[1, 1, 1, 1, 1, 1]);
    let (mut i2c, mut delay) = ring.release();
    i2c.done();
    delay.done();
}

#[test]
fn lingering_echoes_tag_more_neighbours_and_unscheduled_read_nan() {
    // Two groups 10 ms apart: a third of the 29.2 ms lifetime has passed, so the previous group
    // still counts. Transducer 5 is disabled.
    let sched = Schedule::<6, 2>::new(&ring(), &[&[0, 2, 4], &[1, 3]], 0.01, 343.0).unwrap();
    let expect = [
        start(0x70),
        start(0x72),
        start(0x74),
        read(0x70, 100),
        read(0x72, 200),
        read(0x74, 300),
        start(0x71),
        start(0x73),
        read(0x71, 150),
        read(0x73, 250),
    ];
    let i2c = I2cMock::new(&expect);
    let delay = CheckedDelay::new(&[D::delay_us(10_000), D::delay_us(10_000)]);
    let mut ring = SonarRing::new(i2c, delay, &ADDR, sched)
        .map_err(|e| e.0)
        .unwrap();
    let mut out = RingScan::<6>::default();
    ring.read_cycle(&mut out).unwrap();
    assert!(out.scan.ranges_m()[5].is_nan());
    assert!((out.scan.ranges_m()[3] - 2.5).abs() < 1e-6);
    // 0 (group 0): 2, 4 in its group, 1, 3 fired 10 ms before in the cyclic schedule → 4.
    // 1 (group 1): 3, and 0, 2, 4 fired 10 ms before → 4. 5: never fired → 0.
    assert_eq!(out.cofired.as_slice(), &[4, 4, 4, 4, 4, 0]);
    let (mut i2c, mut delay) = ring.release();
    i2c.done();
    delay.done();
}

#[test]
fn bus_error_is_wrapped_and_stops_the_cycle() {
    let sched = Schedule::<6, 3>::new(&ring(), &[&[0, 3], &[1, 4], &[2, 5]], 0.07, 343.0).unwrap();
    let fail = ErrorKind::ArbitrationLoss;
    let expect = [
        start(0x70),
        start(0x73),
        read(0x70, 123),
        read(0x73, 10).with_error(fail),
    ];
    let i2c = I2cMock::new(&expect);
    let delay = CheckedDelay::new(&[D::delay_us(70_000)]);
    let mut ring = SonarRing::new(i2c, delay, &ADDR, sched)
        .map_err(|e| e.0)
        .unwrap();
    let mut out = RingScan::<6>::default();
    assert_eq!(ring.read_cycle(&mut out), Err(Error::I2c(fail)));
    assert!((out.scan.ranges_m()[0] - 1.23).abs() < 1e-6);
    assert!(out.scan.ranges_m()[3].is_nan());
    let (mut i2c, mut delay) = ring.release();
    i2c.done();
    delay.done();
}

#[test]
fn bad_configuration_gives_the_bus_back() {
    let sched = || Schedule::<6, 3>::new(&ring(), &[&[0, 1, 2, 3, 4, 5]], 0.03, 343.0).unwrap();
    let cases: [(&[u8], ConfigError); 3] = [
        (&ADDR[..5], ConfigError::AddressCount { given: 5, ring: 6 }),
        (
            &[0x70, 0x71, 0x72, 0x73, 0x74, 0x78],
            ConfigError::BadAddress(0x78),
        ),
        (
            &[0x70, 0x71, 0x72, 0x73, 0x74, 0x70],
            ConfigError::DuplicateAddress(0x70),
        ),
    ];
    for (addrs, want) in cases {
        let i2c = I2cMock::new(&[]);
        let delay = CheckedDelay::new(&[]);
        let Err((e, mut i2c, mut delay)) = SonarRing::new(i2c, delay, addrs, sched()) else {
            panic!("{want:?} accepted");
        };
        assert_eq!(e, want);
        i2c.done();
        delay.done();
    }
}
