//! The firmware a robot's base controller runs: the LD06's bytes in on USART1 and wheel
//! odometry and commands in on USART2, each received in its interrupt handler into a lock-free
//! ring; the localizer ([`beamfield::robot::Robot`]) in the main loop; estimates, heartbeats and
//! typed errors out on USART3 (the link protocol, `docs/link-protocol.md`); `cargo xtask robot`
//! plays the robot around it. The board (its clocks, pins and lines) is
//! `beamfield_firmware::boards`: the STM32F405 (QEMU `netduinoplus2`) by default, the
//! STM32L475 (QEMU `b-l475e-iot01a`) with the feature `board-b-l475e-iot01a`. On both the Nth
//! `-serial` is USART N.
//!
//! The map (the Intel lab's 5 cm distance field, tiled, and its free space) is linked into flash; the
//! setup is `fixtures/src/robot_plan.rs`, which the host's replay uses too. The last good
//! estimate is kept in RAM that a reset does not clear ([`SeedStore`]; a flash page on a
//! product) and seeds the next start.
//!
//! Features: `count` marks the stages of every poll for the instruction counter (interrupts
//! masked inside each counted region, so the counts are exact, and the main loop waits for a
//! chunk of bytes (or 500 ms) before it polls, so the regions stay few); `count-isr` marks every run of the
//! receive interrupt handlers instead; `emulator` ends the program (semihosting exit) once the
//! LiDAR has been silent for [`EXIT_AFTER_MS`], printing the counters.
#![no_std]
#![no_main]

use beamfield::field::FreeSpace;
use beamfield::link::Message;
use beamfield::robot::{ByteSource, Probe, Robot, Seed, Sink, Stage};
use beamfield::FieldView;
#[cfg(feature = "board-b-l475e-iot01a")]
use beamfield_firmware::boards::b_l475e_iot01a as board;
#[cfg(not(feature = "board-b-l475e-iot01a"))]
use beamfield_firmware::boards::netduinoplus2 as board;
use beamfield_firmware::serial::Backpressure;
use beamfield_firmware::{exit, println};
use beamfield_fixtures::robot_plan::{self, baud, ring, BEAMS, CAPACITY};
use board::Irq;
use core::cell::RefCell;
use core::sync::atomic::{AtomicU32, Ordering};
use cortex_m::interrupt::InterruptNumber;
use cortex_m::interrupt::Mutex;
use cortex_m::peripheral::syst::SystClkSource;
use cortex_m::peripheral::NVIC;
use cortex_m_rt::{entry, exception};
use heapless::spsc::{Consumer, Producer, Queue};
#[cfg(feature = "defmt")]
use panic_probe as _;
#[cfg(not(feature = "defmt"))]
use panic_semihosting as _;

/// The 5 cm distance field of the Intel map (the demo's, `docs/demo.md`), tiled with the
/// feature `tiled` (297,640 bytes, the same distances bit for bit; `docs/blob-format.md`), else
/// raw (781,063 bytes). `cargo xtask robot` builds it tiled.
#[cfg(feature = "tiled")]
static BLOB: &[u8] = include_bytes!("../../assets/intel-tiled.bin");
#[cfg(not(feature = "tiled"))]
static BLOB: &[u8] = include_bytes!("../../assets/intel.bin");
/// Its known-free cells, for global localization (`docs/free-space-format.md`).
static FREE: &[u8] = include_bytes!("../../assets/intel-free-space.bin");

/// With the feature `emulator`: silence on both input lines after which the program ends, ms.
#[cfg(feature = "emulator")]
const EXIT_AFTER_MS: u32 = 3_000;
/// With the feature `count`: LiDAR bytes the main loop waits for before it polls (or 500 ms).
#[cfg(feature = "count")]
const COUNT_CHUNK: usize = 1024;

/// The receive rings' producer ends, owned by the interrupt handlers.
static LIDAR_IN: Mutex<RefCell<Option<Producer<'static, u8>>>> = Mutex::new(RefCell::new(None));
static LINK_IN: Mutex<RefCell<Option<Producer<'static, u8>>>> = Mutex::new(RefCell::new(None));
static LIDAR_STATE: Backpressure = Backpressure::new();
static LINK_STATE: Backpressure = Backpressure::new();
/// Milliseconds since start (SysTick).
static MILLIS: AtomicU32 = AtomicU32::new(0);

fn on_rx(line: Irq, ring: &Mutex<RefCell<Option<Producer<'static, u8>>>>, state: &Backpressure) {
    #[cfg(feature = "count-isr")]
    beamfield_firmware::bench_mark_start();
    cortex_m::interrupt::free(|cs| {
        if let Some(p) = ring.borrow(cs).borrow_mut().as_mut() {
            board::on_rx(line, p, state);
        }
    });
    #[cfg(feature = "count-isr")]
    beamfield_firmware::bench_mark_end();
}

/// Every device interrupt lands here (no device vector table is linked: the programs share
/// one runtime setup with the MPS2 board's): the board's LiDAR and link receive interrupts.
#[exception]
#[allow(unsafe_code)]
unsafe fn DefaultHandler(irqn: i16) {
    if irqn == board::LIDAR_IRQ.number() as i16 {
        on_rx(board::LIDAR_IRQ, &LIDAR_IN, &LIDAR_STATE);
    } else if irqn == board::LINK_IRQ.number() as i16 {
        on_rx(board::LINK_IRQ, &LINK_IN, &LINK_STATE);
    }
}

#[exception]
fn SysTick() {
    MILLIS.fetch_add(1, Ordering::Relaxed);
}

fn millis() -> u32 {
    MILLIS.load(Ordering::Relaxed)
}

/// The board's monotonic clock for [`Robot::tick`]: SysTick's milliseconds as µs since start,
/// carried past the `u32`'s wrap (read at least once every 49 days: every turn of the loop).
struct BoardClock {
    last_ms: u32,
    us: u64,
}

impl BoardClock {
    fn new() -> Self {
        Self {
            last_ms: millis(),
            us: u64::from(millis()) * 1000,
        }
    }

    fn now_us(&mut self) -> u64 {
        let ms = millis();
        self.us = self
            .us
            .saturating_add(u64::from(ms.wrapping_sub(self.last_ms)) * 1000);
        self.last_ms = ms;
        self.us
    }
}

/// The last good estimate, in RAM that a reset leaves alone (`.uninit`): a magic word, the
/// pose and covariance as f32 bit patterns, and a checksum. A product keeps it in a flash page
/// instead (written only when the pose has moved, to spare the flash).
struct SeedStore;

const SEED_MAGIC: u32 = 0x5EED_B0B0;
const SEED_WORDS: usize = 12;

#[link_section = ".uninit.beamfield_seed"]
static mut SEED_WORDS_RAM: core::mem::MaybeUninit<[u32; SEED_WORDS]> =
    core::mem::MaybeUninit::uninit();

fn seed_checksum(words: &[u32]) -> u32 {
    words
        .iter()
        .fold(0x811C_9DC5u32, |h, &w| (h ^ w).wrapping_mul(0x0100_0193))
}

impl SeedStore {
    fn words() -> [u32; SEED_WORDS] {
        // SAFETY: plain words in RAM; any bit pattern is a valid `[u32; N]` and only the main
        // loop touches them (no interrupt handler does).
        #[allow(unsafe_code)]
        unsafe {
            core::ptr::read_volatile(
                core::ptr::addr_of!(SEED_WORDS_RAM).cast::<[u32; SEED_WORDS]>(),
            )
        }
    }

    fn load() -> Option<Seed> {
        let w = Self::words();
        let (body, sum) = w.split_at(SEED_WORDS - 1);
        if w.first() != Some(&SEED_MAGIC) || sum.first() != Some(&seed_checksum(body)) {
            return None;
        }
        let f = |i: usize| f32::from_bits(w.get(i).copied().unwrap_or(0));
        let seed = Seed {
            pose: beamfield::Pose::new(f(1), f(2), f(3)),
            covariance: [[f(4), f(5), f(6)], [f(5), f(7), f(8)], [f(6), f(8), f(9)]],
        };
        seed.pose.is_finite().then_some(seed)
    }

    fn save(seed: &Seed) {
        let c = &seed.covariance;
        let mut w = [
            SEED_MAGIC,
            seed.pose.x_m.to_bits(),
            seed.pose.y_m.to_bits(),
            seed.pose.theta_rad.to_bits(),
            c[0][0].to_bits(),
            c[0][1].to_bits(),
            c[0][2].to_bits(),
            c[1][1].to_bits(),
            c[1][2].to_bits(),
            c[2][2].to_bits(),
            0,
            0,
        ];
        w[SEED_WORDS - 1] = seed_checksum(&w[..SEED_WORDS - 1]);
        // SAFETY: as in `words`.
        #[allow(unsafe_code)]
        unsafe {
            core::ptr::write_volatile(
                core::ptr::addr_of_mut!(SEED_WORDS_RAM).cast::<[u32; SEED_WORDS]>(),
                w,
            )
        }
    }
}

/// Frames go into the transmit ring (whole, or not at all) and the estimate into the store.
struct TxSink {
    ring: Producer<'static, u8>,
    frames: u32,
    dropped: u32,
    saved: u32,
}

impl Sink for TxSink {
    fn send(&mut self, _message: &Message, wire: &[u8]) {
        let room = self.ring.capacity() - self.ring.len();
        if wire.len() > room {
            self.dropped += 1;
            return;
        }
        for &b in wire {
            let _ = self.ring.enqueue(b);
        }
        self.frames += 1;
    }

    fn save(&mut self, seed: &Seed) {
        SeedStore::save(seed);
        self.saved += 1;
    }
}

/// Counted regions (feature `count`): the stage's name, then the markers, with interrupts
/// masked so the count is the stage's work alone.
struct CountProbe;

impl Probe for CountProbe {
    fn enter(&mut self, stage: Stage) {
        #[cfg(feature = "count")]
        {
            use beamfield_fixtures::regions::robot as r;
            cortex_m::interrupt::disable();
            let name = match stage {
                Stage::Link => r::LINK.name,
                Stage::Lidar => r::LIDAR.name,
                Stage::Predict => r::PREDICT.name,
                Stage::Update => r::UPDATE.name,
                Stage::Send => r::SEND.name,
            };
            beamfield_firmware::start_region!(name);
        }
        #[cfg(not(feature = "count"))]
        let _ = stage;
    }

    fn leave(&mut self, _stage: Stage) {
        #[cfg(feature = "count")]
        {
            beamfield_firmware::bench_mark_end();
            // SAFETY: re-enables what `enter` masked; no critical section spans the region.
            #[allow(unsafe_code)]
            unsafe {
                cortex_m::interrupt::enable()
            };
        }
    }
}

/// A ring's consumer end that remembers when it last gave a byte.
struct Input<'q> {
    ring: Consumer<'q, u8>,
    taken: u32,
}

impl ByteSource for Input<'_> {
    #[inline]
    fn next_byte(&mut self) -> Option<u8> {
        let b = self.ring.dequeue()?;
        self.taken = self.taken.wrapping_add(1);
        Some(b)
    }
}

#[entry]
fn main() -> ! {
    let Some(mut cp) = cortex_m::Peripherals::take() else {
        println!("robot: peripherals taken twice");
        exit(false)
    };
    let Some(store) = cortex_m::singleton!(: beamfield::mcl::Particles<CAPACITY> = beamfield::mcl::Particles::new())
    else {
        println!("robot: particle storage taken twice");
        exit(false)
    };
    let (Some(lidar_q), Some(link_q), Some(tx_q)) = (
        cortex_m::singleton!(: Queue<u8, { ring::LIDAR }> = Queue::new()),
        cortex_m::singleton!(: Queue<u8, { ring::LINK_IN }> = Queue::new()),
        cortex_m::singleton!(: Queue<u8, { ring::LINK_OUT }> = Queue::new()),
    ) else {
        println!("robot: rings taken twice");
        exit(false)
    };
    let setup = set_up(store);
    let mut robot = match setup {
        Ok(r) => r,
        Err(e) => {
            println!("robot: setup refused: {}", e);
            exit(false)
        }
    };
    let seeded = robot.is_initialized();

    let (lidar_p, lidar_c) = lidar_q.split();
    let (link_p, link_c) = link_q.split();
    let (tx_p, mut tx_c) = tx_q.split();
    cortex_m::interrupt::free(|cs| {
        LIDAR_IN.borrow(cs).replace(Some(lidar_p));
        LINK_IN.borrow(cs).replace(Some(link_p));
    });
    let mut lidar = Input {
        ring: lidar_c,
        taken: 0,
    };
    let mut link = Input {
        ring: link_c,
        taken: 0,
    };
    let mut sink = TxSink {
        ring: tx_p,
        frames: 0,
        dropped: 0,
        saved: 0,
    };

    let started = match board::init([baud::LIDAR, baud::LINK_IN, baud::LINK_OUT]) {
        Ok(s) => s,
        Err(e) => {
            println!("robot: {}: {}", board::NAME, e);
            exit(false)
        }
    };
    // 1 ms ticks from the core clock the board reports.
    let Some(reload) = beamfield_fixtures::clocks::systick_reload(started.clocks.hclk_hz, 1_000)
    else {
        println!(
            "robot: no 1 ms SysTick reload from {} Hz",
            started.clocks.hclk_hz
        );
        exit(false)
    };
    let c = &started.clocks;
    println!(
        "robot: clocks: {}: SYSCLK {} Hz ({:?}; {}), HCLK {} Hz, APB1 {} Hz, APB2 {} Hz, flash {} wait states; SysTick reload {}; USART BRR {:?}",
        board::NAME,
        c.sysclk_hz,
        c.source,
        started.note,
        c.hclk_hz,
        c.pclk1_hz,
        c.pclk2_hz,
        started.wait_states,
        reload,
        started.brr
    );
    cp.SYST.set_clock_source(SystClkSource::Core);
    cp.SYST.set_reload(reload);
    cp.SYST.clear_current();
    cp.SYST.enable_counter();
    cp.SYST.enable_interrupt();
    // SAFETY: the handlers only touch their rings' producer ends and the counters; nothing in
    // the main loop relies on them being masked.
    #[allow(unsafe_code)]
    unsafe {
        NVIC::unmask(board::LIDAR_IRQ);
        NVIC::unmask(board::LINK_IRQ);
        cortex_m::interrupt::enable();
    }
    println!(
        "robot: ready: USART1 LD06 in at {} baud (ring {} B), USART2 link in at {} baud (ring {} B), USART3 link out at {} baud; {} of {} particles, {} beams; {}",
        baud::LIDAR,
        ring::LIDAR,
        baud::LINK_IN,
        ring::LINK_IN,
        baud::LINK_OUT,
        robot.config().particles,
        CAPACITY,
        BEAMS,
        if seeded { "seeded from the stored estimate" } else { "waiting for an initial pose" }
    );

    let mut probe = CountProbe;
    let (mut last_lidar_ms, mut last_link_ms) = (millis(), millis());
    let mut clock = BoardClock::new();
    let (mut lidar_peak, mut link_peak) = (0usize, 0usize);
    let mut overruns_reported = 0u32;
    let mut tx_bytes = 0u32;
    #[cfg(feature = "count")]
    let mut last_poll_ms = millis();
    loop {
        lidar_peak = lidar_peak.max(lidar.ring.len());
        link_peak = link_peak.max(link.ring.len());
        #[cfg(feature = "count")]
        {
            // Few, large regions: poll once a chunk has arrived or the line went quiet.
            if lidar.ring.len() < COUNT_CHUNK
                && millis().wrapping_sub(last_poll_ms) < 500
                && link.ring.len() < link.ring.capacity()
            {
                cortex_m::asm::wfi();
                continue;
            }
            last_poll_ms = millis();
        }
        let (lidar_before, link_before) = (lidar.taken, link.taken);
        let progress = robot.poll_probed(&mut lidar, &mut link, &mut sink, &mut probe);
        let now = millis();
        if lidar.taken != lidar_before {
            last_lidar_ms = now;
        }
        if link.taken != link_before {
            last_link_ms = now;
        }
        board::resume(
            board::LIDAR_IRQ,
            lidar.ring.len() < lidar.ring.capacity(),
            &LIDAR_STATE,
        );
        board::resume(
            board::LINK_IRQ,
            link.ring.len() < link.ring.capacity(),
            &LINK_STATE,
        );
        // Bytes the hardware lost (overruns) are drops the computer should hear of.
        let overruns = LIDAR_STATE
            .overruns
            .load(Ordering::Relaxed)
            .wrapping_add(LINK_STATE.overruns.load(Ordering::Relaxed));
        if overruns != overruns_reported {
            robot.add_drops(overruns.wrapping_sub(overruns_reported));
            overruns_reported = overruns;
        }
        // The board's clock: a heartbeat every period whatever the LiDAR sends, and the link
        // read at its pace once the LiDAR has sent no valid frame for a while.
        robot.tick(clock.now_us(), &mut sink);
        tx_bytes = tx_bytes.wrapping_add(board::pump(&mut tx_c));
        #[cfg(feature = "emulator")]
        if now.wrapping_sub(last_lidar_ms) >= EXIT_AFTER_MS
            && now.wrapping_sub(last_link_ms) >= EXIT_AFTER_MS
            && !tx_c.ready()
        {
            report(&robot, &sink, tx_bytes, (lidar_peak, link_peak), seeded);
            exit(sink.dropped == 0)
        }
        let _ = (last_lidar_ms, last_link_ms);
        if progress.is_idle() && !tx_c.ready() {
            cortex_m::asm::wfi();
        }
    }
}

/// The localizer over the linked map, with the shared setup and the stored estimate.
fn set_up(
    store: &'static mut beamfield::mcl::Particles<CAPACITY>,
) -> Result<Robot<'static, CAPACITY, BEAMS>, beamfield::Error> {
    let view = FieldView::parse(BLOB)?;
    let free = FreeSpace::parse(FREE)?;
    let layout =
        robot_plan::layout().map_err(|_| beamfield::Error::Scan(beamfield::ScanError::BadStep))?;
    let config = robot_plan::config()?;
    Robot::new(store, view, Some(free), layout, config, SeedStore::load())
}

/// The run's counters, one line per source (printed by `cargo xtask robot`).
#[cfg(feature = "emulator")]
fn report(
    robot: &Robot<'_, CAPACITY, BEAMS>,
    sink: &TxSink,
    tx_bytes: u32,
    peaks: (usize, usize),
    seeded: bool,
) {
    let c = robot.counters();
    let d = robot.lidar_stats();
    let a = robot.assembler_stats();
    let l = robot.link_stats();
    println!(
        "robot: lidar in: {} bytes into the ring, peak {} of {} bytes, {} times full, {} overruns, {} line errors; decoder {} bytes, {} frames ok, {} bad checksums, {} bytes skipped; assembler {} points, {} accepted, {} revolutions",
        LIDAR_STATE.received.load(Ordering::Relaxed),
        peaks.0,
        ring::LIDAR,
        LIDAR_STATE.full.load(Ordering::Relaxed),
        LIDAR_STATE.overruns.load(Ordering::Relaxed),
        LIDAR_STATE.line_errors.load(Ordering::Relaxed),
        d.bytes,
        d.frames_ok,
        d.bad_checksum,
        d.skipped_bytes,
        a.points,
        a.accepted,
        a.revolutions,
    );
    println!(
        "robot: link in: {} bytes into the ring, peak {} of {} bytes, {} times full, {} overruns; decoder {} bytes, {} frames, {} errors ({} bad CRC); {} odometry messages, {} commands carried out, {} refused",
        LINK_STATE.received.load(Ordering::Relaxed),
        peaks.1,
        ring::LINK_IN,
        LINK_STATE.full.load(Ordering::Relaxed),
        LINK_STATE.overruns.load(Ordering::Relaxed),
        l.bytes,
        l.frames,
        l.errors(),
        l.bad_crc,
        c.odometry,
        c.commands,
        c.refused,
    );
    println!(
        "robot: filter: {} revolutions, {} updates, {} skipped, {} with late odometry, {} flagged stale; link out: {} frames ({} bytes), {} dropped for a full ring, {} not encodable; {} estimates saved{}",
        c.revolutions,
        c.updates,
        c.skipped,
        c.late_odometry,
        c.stale_odometry,
        sink.frames,
        tx_bytes,
        sink.dropped,
        c.encode_failures,
        sink.saved,
        if seeded { "; started from a stored estimate" } else { "" },
    );
}
