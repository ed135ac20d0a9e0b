//! Budgets on the target (`cargo xtask budgets` runs this under the QEMU counting plugin):
//! instructions per pose and per beam of the likelihood field and of the beam model with ray
//! casting, and the stack high-water mark of one scoring call of each.
//!
//! Input: the Intel-lab blob (the demo's) and a 360-beam scan in 1° steps from −90°: beams
//! 0–179 are the real readings of the first embedded Intel scan (its laser covers −90° … +89°),
//! beams 180–359 (behind the laser) are ray cast through the blob from the logged pose. The
//! hypotheses are `POSES` poses on a line near the logged pose.
//!
//! Measured regions, in order, each between `bench_mark_start`/`bench_mark_end` and named right
//! before it (`start_region`, the names of `beamfield_fixtures::regions::budget`; the task takes
//! the counts by name); before them the program prints one line per region,
//! `budget: region <name> poses <p> beams <b>`:
//! `lf` and `lf-half` (the likelihood field over every beam and over every second one: their
//! difference is the marginal cost of a beam), `tempered` (the tempered likelihood field),
//! `normalize` (normalizing `POSES` log-weights), `beam` and `beam-half` (the beam model with
//! ray casting), then `lf-prepared` and `lf-prepared-half` (the likelihood field through a
//! [`PreparedScan`] made once before the region, over its kept beams; the form a pose-scoring
//! loop uses).
//!
//! Stack: `budget: stack <name> <bytes>`, the deepest word written below the caller's stack
//! pointer by one call (the region is painted with a pattern first, then scanned), and
//! `budget: state <name> <bytes>`, the sizes of the values a caller keeps.
#![no_std]
#![no_main]

use beamfield::{
    normalize_log_weights, BeamFieldModel, BeamIntrinsics, BeamLayout, BeamModel, FieldView,
    LikelihoodField, LikelihoodParams, Pose, PreparedScan, RayCaster, Scan, SensorModel,
    SensorMount, Stride, Tempered,
};
use beamfield_firmware::{bench_mark_end, exit, println, start_region};
use beamfield_fixtures::regions::budget;
use core::hint::black_box;
use cortex_m_rt::entry;
use panic_semihosting as _;

use beamfield_fixtures::demo_scans::{MAX_RANGE_M, SCANS};
use beamfield_fixtures::intel_setup::BEAMS as LOG_BEAMS;

/// The 5 cm distance field of the Intel map.
static BLOB: &[u8] = include_bytes!("../../assets/intel.bin");

/// Beams per scan: the budgets are stated for 360.
const BEAMS: usize = 360;
/// Pose hypotheses per measured region.
const POSES: usize = 8;
/// Bytes painted below the stack pointer before a measured call.
const PAINT_BYTES: usize = 16 * 1024;
/// Bytes right below the stack pointer left unpainted (the measuring function's own use).
const GUARD_BYTES: usize = 64;
/// The paint.
const PAINT: u32 = 0x5AC4_E17D;

extern "C" {
    /// End of `.bss` and `.uninit` (cortex-m-rt's linker script): the stack must not be
    /// painted below it.
    static __sheap: u32;
}

/// Everything a scoring call reads.
struct Ctx<'a> {
    field: LikelihoodField<'a>,
    tempered: Tempered<LikelihoodField<'a>>,
    beam: BeamFieldModel<'a>,
    layout: BeamLayout<BEAMS>,
    scan: Scan<BEAMS>,
    poses: [Pose; POSES],
    weights: [f32; POSES],
}

/// A measured scoring call.
type Call = fn(&mut Ctx<'_>) -> f32;

/// The deepest stack use below the caller's frame of `f(ctx)`, bytes, and its result.
///
/// Paints `[sp − PAINT_BYTES, sp − GUARD_BYTES)` with `PAINT`, calls `f` through an opaque
/// function pointer (so it is not inlined into this frame), then finds the lowest word that is
/// no longer `PAINT`. A result of `GUARD_BYTES` or less means "at most that". `None` if the
/// painted region would reach `.bss`.
#[inline(never)]
fn stack_use(f: Call, ctx: &mut Ctx<'_>) -> Option<(usize, f32)> {
    let sp = cortex_m::register::msp::read() as usize;
    let heap_start = core::ptr::addr_of!(__sheap) as usize;
    let bottom = sp.checked_sub(PAINT_BYTES)?;
    if bottom < heap_start {
        return None;
    }
    let top = sp - GUARD_BYTES;
    let mut p = bottom;
    while p < top {
        // SAFETY: word-aligned addresses in RAM between the end of .bss and the stack
        // pointer, which nothing uses while this runs (no interrupts are enabled).
        unsafe { core::ptr::write_volatile(p as *mut u32, PAINT) };
        p += 4;
    }
    let out = black_box(f)(ctx);
    let mut p = bottom;
    // SAFETY: the same addresses, read back.
    while p < top && unsafe { core::ptr::read_volatile(p as *const u32) } == PAINT {
        p += 4;
    }
    Some((sp - p.min(top), out))
}

#[inline(never)]
fn call_lf(c: &mut Ctx<'_>) -> f32 {
    c.field
        .score(&c.layout, &c.scan, &c.poses[0])
        .log_likelihood
}

#[inline(never)]
fn call_tempered(c: &mut Ctx<'_>) -> f32 {
    c.tempered
        .score(&c.layout, &c.scan, &c.poses[0])
        .log_likelihood
}

#[inline(never)]
fn call_normalize(c: &mut Ctx<'_>) -> f32 {
    match normalize_log_weights(&mut c.weights) {
        Ok(n) => n.ess,
        Err(_) => f32::NAN,
    }
}

#[inline(never)]
fn call_beam(c: &mut Ctx<'_>) -> f32 {
    c.beam.score(&c.layout, &c.scan, &c.poses[0]).log_likelihood
}

/// Sum of `model`'s log-likelihoods over the hypotheses with `stride`, between the markers of
/// the region `name`.
fn region<M: SensorModel<BEAMS>>(name: &str, c: &Ctx<'_>, model: &M, stride: Stride) -> f32 {
    let layout = black_box(&c.layout);
    let scan = black_box(&c.scan);
    let poses = black_box(&c.poses);
    start_region!(name);
    let mut sum = 0.0f32;
    for pose in poses {
        sum += model
            .score_strided(layout, scan, pose, stride)
            .log_likelihood;
    }
    bench_mark_end();
    sum
}

/// Sum of a prepared scan's log-likelihoods over the hypotheses, between the markers of the
/// region `name`.
fn prepared_region(name: &str, prepared: &PreparedScan<'_, BEAMS>, poses: &[Pose; POSES]) -> f32 {
    let prepared = black_box(prepared);
    let poses = black_box(poses);
    start_region!(name);
    let mut sum = 0.0f32;
    for pose in poses {
        sum += prepared.score(pose).log_likelihood;
    }
    bench_mark_end();
    sum
}

#[entry]
fn main() -> ! {
    let Some(first) = SCANS.first() else {
        exit(false)
    };
    let Ok(view) = FieldView::parse(BLOB) else {
        println!("budget: blob rejected");
        exit(false)
    };
    let (Ok(params), Ok(intrinsics), Ok(caster)) = (
        LikelihoodParams::new(0.95, 0.05, 0.0588, MAX_RANGE_M),
        BeamIntrinsics::amcl_defaults(MAX_RANGE_M),
        RayCaster::new(view),
    ) else {
        println!("budget: parameters rejected");
        exit(false)
    };
    let field = LikelihoodField::new(view, params);
    let Ok(tempered) = Tempered::new(field.clone(), 8.25, 1) else {
        exit(false)
    };
    let Ok(layout) = BeamLayout::<BEAMS>::uniform(
        -core::f32::consts::FRAC_PI_2,
        core::f32::consts::PI / 180.0,
        BEAMS,
        MAX_RANGE_M,
        SensorMount::CENTERED,
    ) else {
        exit(false)
    };
    // The scan: the real front half, the rear half cast from the logged pose.
    let logged = Pose::new(first.pose[0], first.pose[1], first.pose[2]);
    let mut ranges = [0.0f32; BEAMS];
    for (k, (r, beam)) in ranges.iter_mut().zip(layout.beams()).enumerate() {
        *r = match first.ranges_m.get(k) {
            Some(&real) => real,
            None => caster.cast(
                logged.x_m,
                logged.y_m,
                logged.theta_rad + beam.bearing_rad,
                MAX_RANGE_M,
            ),
        };
    }
    let Ok(scan) = Scan::<BEAMS>::from_ranges(&ranges) else {
        exit(false)
    };
    let mut poses = [logged; POSES];
    for (i, p) in poses.iter_mut().enumerate() {
        let d = 0.01 * (i as f32 - (POSES / 2) as f32);
        *p = Pose::new(logged.x_m + d, logged.y_m - d, logged.theta_rad + 0.5 * d);
    }
    let mut ctx = Ctx {
        field,
        tempered,
        beam: BeamFieldModel::new(BeamModel::new(intrinsics), caster),
        layout,
        scan,
        poses,
        weights: [0.0; POSES],
    };
    let half = Stride::new(2).unwrap_or(Stride::ONE);
    let scored = ctx.field.score(&ctx.layout, &ctx.scan, &logged);
    println!(
        "budget: scan {} beams ({} real, {} ray cast), at the logged pose: {} scored, {} max-range",
        BEAMS,
        LOG_BEAMS,
        BEAMS - LOG_BEAMS,
        scored.scored,
        scored.max_range
    );
    // Prepared once, outside the measured regions (the per-scan cost, not per pose).
    let prepared = ctx.field.prepare(&ctx.layout, &ctx.scan);
    let prepared_half = ctx.field.prepare_strided(&ctx.layout, &ctx.scan, half);
    let names: [(&str, usize); 8] = [
        (budget::LF.name, BEAMS),
        (budget::LF_HALF.name, BEAMS.div_ceil(2)),
        (budget::TEMPERED.name, BEAMS),
        (budget::NORMALIZE.name, 0),
        (budget::BEAM.name, BEAMS),
        (budget::BEAM_HALF.name, BEAMS.div_ceil(2)),
        (budget::LF_PREPARED.name, prepared.len()),
        (budget::LF_PREPARED_HALF.name, prepared_half.len()),
    ];
    for (name, beams) in names {
        println!("budget: region {} poses {} beams {}", name, POSES, beams);
    }

    let lf = region(budget::LF.name, &ctx, &ctx.field, Stride::ONE);
    let lf_half = region(budget::LF_HALF.name, &ctx, &ctx.field, half);
    let tempered = region(budget::TEMPERED.name, &ctx, &ctx.tempered, Stride::ONE);
    let mut weights = [0.0f32; POSES];
    for (w, pose) in weights.iter_mut().zip(&ctx.poses) {
        *w = ctx
            .tempered
            .score(&ctx.layout, &ctx.scan, pose)
            .log_likelihood;
    }
    let w = black_box(&mut weights);
    start_region!(budget::NORMALIZE.name);
    let norm = normalize_log_weights(w);
    bench_mark_end();
    let beam = region(budget::BEAM.name, &ctx, &ctx.beam, Stride::ONE);
    let beam_half = region(budget::BEAM_HALF.name, &ctx, &ctx.beam, half);
    let lf_prepared = prepared_region(budget::LF_PREPARED.name, &prepared, &ctx.poses);
    let lf_prepared_half =
        prepared_region(budget::LF_PREPARED_HALF.name, &prepared_half, &ctx.poses);
    let ok_counts = [
        lf,
        lf_half,
        tempered,
        beam,
        beam_half,
        lf_prepared,
        lf_prepared_half,
    ]
    .iter()
    .all(|v| v.is_finite())
        && norm.is_ok();

    ctx.weights = weights;
    let calls: [(&str, Call); 4] = [
        ("lf", call_lf),
        ("tempered", call_tempered),
        ("normalize", call_normalize),
        ("beam", call_beam),
    ];
    let mut ok_stack = true;
    for (name, f) in calls {
        match stack_use(f, &mut ctx) {
            Some((bytes, out)) => {
                ok_stack &= out.is_finite();
                println!("budget: stack {} {}", name, bytes);
            }
            None => {
                println!("budget: stack {} not measured (no room to paint)", name);
                ok_stack = false;
            }
        }
    }
    println!(
        "budget: state lf {}",
        core::mem::size_of::<LikelihoodField<'_>>()
    );
    println!(
        "budget: state tempered {}",
        core::mem::size_of::<Tempered<LikelihoodField<'_>>>()
    );
    println!(
        "budget: state beam {}",
        core::mem::size_of::<BeamFieldModel<'_>>()
    );
    println!(
        "budget: state layout {}",
        core::mem::size_of::<BeamLayout<BEAMS>>()
    );
    println!("budget: state scan {}", core::mem::size_of::<Scan<BEAMS>>());
    println!(
        "budget: state prepared {}",
        core::mem::size_of::<PreparedScan<'_, BEAMS>>()
    );
    println!(
        "budget: state weights {}",
        core::mem::size_of::<[f32; POSES]>()
    );
    exit(ok_counts && ok_stack)
}
