//! The QEMU mps2-an386 image: replay a sensor log read over semihosting through the pipeline,
//! stream defmt frames over semihosting, then measure the instruction counts and exit through
//! semihosting with a status.
//!
//! The plan (structure, rate, detector, model) is compiled in ([`crate::plan`]); the log
//! header is only checked against it (any difference: status [`status::SCENE_MISMATCH`]).
//!
//! The log path is the last word of the semihosting command line (QEMU `-append <path>`,
//! relative to QEMU's working directory), else `SSVR_QEMU_LOG` at build time, else
//! `sensor.ssvrlog`.

mod queue;
mod semihosting;

use crate::stream;
use crate::{bench, plan, stack};
use heapless::spsc::Queue;
use queue::{FrameProducer, QUEUE_LEN};
use semihosting::{exit, log_path, HostFile, Reader};
use ssvr_proto::log::{
    self, options, Header, LogError, COUNT_UNTIL_EOF, HEADER_LEN, RECORD_LEN, REVERSAL_LEN,
};
use ssvr_proto::{EventSource, Frame, Plan, Sample, BATCH};

use defmt_semihosting as _;

/// Exit statuses of the QEMU image.
pub mod status {
    /// Log replayed and benchmark done.
    pub const OK: u32 = 0;
    /// A panic (should not happen).
    pub const PANIC: u32 = 101;
    /// The log could not be opened.
    pub const LOG_OPEN: u32 = 2;
    /// The log header is invalid.
    pub const LOG_HEADER: u32 = 3;
    /// The compiled-in structure or estimator coefficients are invalid or the
    /// estimator/detector refused them (build.rs validates the scene, so this should not happen).
    pub const STRUCTURE: u32 = 4;
    /// The log could not be read or is truncated.
    pub const LOG_READ: u32 = 5;
    /// Core peripherals unavailable.
    pub const PERIPHERALS: u32 = 6;
    /// The log header's sample rate or structure differs from the compiled-in scene.
    pub const SCENE_MISMATCH: u32 = 7;
}

/// The first header field that differs from the compiled-in scene: (name, log, firmware).
/// Exact comparison: host-sim writes the scene's own f64 values.
fn scene_mismatch(h: &Header, plan: &Plan) -> Option<(&'static str, f64, f64)> {
    let (p, c) = (&h.params, &plan.specimen.structure);
    [
        (
            "sample_rate_hz",
            h.sample_rate_hz,
            plan.specimen.sample_rate_hz,
        ),
        ("m1_kg", p.m1_kg, c.m1_kg),
        ("m2_kg", p.m2_kg, c.m2_kg),
        (
            "natural_frequency_hz",
            p.natural_frequency_hz,
            c.natural_frequency_hz,
        ),
        ("damping_ratio", p.damping_ratio, c.damping_ratio),
        (
            "friction_coefficient",
            p.friction_coefficient,
            c.friction_coefficient,
        ),
        ("gravity_m_s2", p.gravity_m_s2, c.gravity_m_s2),
    ]
    .into_iter()
    .find(|&(_, log, fw)| log != fw)
}

/// Replay the log, run the benchmark, exit.
pub fn run() -> ! {
    let Some(cp) = cortex_m::Peripherals::take() else {
        defmt::error!("core peripherals already taken");
        exit(status::PERIPHERALS)
    };
    let painted = stack::paint();
    let mut ticks = bench::Ticks::new(cp.SYST);
    let plan = plan::PLAN;
    plan::emit();

    let mut cmdline = [0u8; 256];
    let path = log_path(&mut cmdline);
    let file = match HostFile::open(path) {
        Ok(f) => f,
        Err(e) => {
            defmt::error!("cannot open sensor log {=[u8]:a}: {}", path, e);
            exit(status::LOG_OPEN)
        }
    };
    let mut reader = Reader::new(file);

    let mut hb = [0u8; HEADER_LEN];
    let header = match reader
        .read_exact(&mut hb)
        .and_then(|full| {
            if full {
                Ok(())
            } else {
                Err(LogError::Truncated)
            }
        })
        .and_then(|()| log::parse_header(&hb))
    {
        Ok(h) => h,
        Err(e) => {
            defmt::error!("bad sensor log header: {}", e);
            exit(status::LOG_HEADER)
        }
    };
    // Skip header bytes of a later minor revision.
    let mut extra = usize::from(header.header_len) - HEADER_LEN;
    while extra > 0 {
        let mut skip = [0u8; 16];
        let n = extra.min(skip.len());
        match reader.read_exact(&mut skip[..n]) {
            Ok(true) => extra -= n,
            _ => {
                defmt::error!("sensor log header truncated");
                exit(status::LOG_HEADER)
            }
        }
    }
    let p = &header.params;
    defmt::info!(
        "log rate_hz={=f64} samples={=u32} options={=u16} m1={=f64} m2={=f64} f_hz={=f64} xi={=f64} mu={=f64} g={=f64}",
        header.sample_rate_hz,
        header.sample_count,
        header.options,
        p.m1_kg,
        p.m2_kg,
        p.natural_frequency_hz,
        p.damping_ratio,
        p.friction_coefficient,
        p.gravity_m_s2
    );
    if let Some((field, log, fw)) = scene_mismatch(&header, &plan) {
        defmt::error!(
            "log header does not match the compiled-in scene: {=str} log={=f64} firmware={=f64} (rebuild with SSVR_SCENE)",
            field,
            log,
            fw
        );
        exit(status::SCENE_MISMATCH)
    }
    let source = if header.options & options::LOG_REVERSALS != 0 {
        EventSource::Log
    } else {
        EventSource::Detector
    };

    let mut pipe = match plan::pipeline(&plan, source) {
        Ok(p) => p,
        Err(e) => {
            defmt::error!("the compiled-in plan cannot run: {}", e);
            exit(status::STRUCTURE)
        }
    };
    let mut queue: Queue<Frame, QUEUE_LEN> = Queue::new();
    let (producer, mut consumer) = queue.split();
    let mut producer = FrameProducer::new(producer);
    let mut n: u32 = 0;
    let mut read_error = None;
    // Samples are replayed in batches of BATCH (the pipeline's estimator block); the queue is
    // drained after each (the streaming loop's turn), and the last, partial batch is processed
    // whatever ends the log.
    let mut batch = [Sample::missing(0); BATCH];
    let mut queued = 0;
    while header.sample_count == COUNT_UNTIL_EOF || n < header.sample_count {
        let mut rb = [0u8; RECORD_LEN];
        match reader.read_exact(&mut rb) {
            Ok(true) => {}
            Ok(false) if header.sample_count == COUNT_UNTIL_EOF => break,
            Ok(false) => {
                read_error = Some(LogError::Truncated);
                break;
            }
            Err(e) => {
                read_error = Some(e);
                break;
            }
        }
        let (mut sample, has_reversal) = log::parse_record(&rb);
        if has_reversal {
            let mut ev = [0u8; REVERSAL_LEN];
            match reader.read_exact(&mut ev) {
                Ok(true) => sample.reversal = Some(log::parse_reversal(&ev)),
                Ok(false) | Err(_) => {
                    read_error = Some(LogError::Truncated);
                    break;
                }
            }
        }
        if let Some(b) = batch.get_mut(queued) {
            *b = sample;
            queued += 1;
        }
        n += 1;
        if queued == BATCH {
            producer.produce_batch(&mut pipe, &batch);
            queued = 0;
            let _ = stream::drain(&mut consumer);
        }
    }
    producer.produce_batch(&mut pipe, batch.get(..queued).unwrap_or(&[]));
    let _ = stream::drain(&mut consumer);
    ssvr_proto::stream::emit_stats(&pipe.stats);
    stream::emit_mu(&pipe);
    if let Some(e) = read_error {
        defmt::error!("sensor log read failed after {=u32} samples: {}", n, e);
        exit(status::LOG_READ)
    }

    let bench_plan = bench::plan_for(&plan);
    match (plan::model(&bench_plan), plan::detector(&bench_plan)) {
        (Ok(m), Ok(d)) => bench::run(&mut ticks, &bench_plan, m, d),
        _ => exit(status::STRUCTURE),
    }
    stack::report(&painted);
    defmt::info!("done");
    exit(status::OK)
}

/// Panics should not happen (no data path can panic); report the location and exit.
#[panic_handler]
fn panic(info: &core::panic::PanicInfo) -> ! {
    match info.location() {
        Some(l) => defmt::error!("panic at {=str}:{=u32}", l.file(), l.line()),
        None => defmt::error!("panic"),
    }
    exit(status::PANIC)
}
