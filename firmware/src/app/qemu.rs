//! The QEMU mps2-an386 image: replay a sensor log read over semihosting through the pipeline
//! (reversal detector on the displacement + estimator), stream defmt frames over semihosting,
//! then measure the instruction counts and exit through semihosting with a status.
//!
//! The structure, the sample rate and the detector settings are compiled in from the scene
//! (`SSVR_SCENE` at build time, see [`super::scene`]); the log header is only checked against
//! them (any difference: status [`status::SCENE_MISMATCH`]).
//!
//! The log path is the last word of the semihosting command line (QEMU `-append <path>`,
//! relative to QEMU's working directory), else `SSVR_QEMU_LOG` at build time, else
//! `sensor.ssvrlog`.

use super::pipeline::{self, EventSource, FrameOut, Pipeline, Sample, BATCH, QUEUE_LEN};
use super::sensor_log::{
    self, options, Header, LogError, COUNT_UNTIL_EOF, HEADER_LEN, RECORD_LEN, REVERSAL_LEN,
};
use super::{bench, model, scene, stack};
use cortex_m_semihosting::nr;
use heapless::spsc::Queue;

use defmt_semihosting as _;

/// Default log file name (relative to QEMU's working directory).
pub const DEFAULT_LOG: &str = match option_env!("SSVR_QEMU_LOG") {
    Some(p) => p,
    None => "sensor.ssvrlog",
};

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

/// Exit QEMU with `code` (SYS_EXIT_EXTENDED, ADP_Stopped_ApplicationExit + subcode: QEMU exits
/// with that status).
pub fn exit(code: u32) -> ! {
    let block = [0x2_0026usize, code as usize];
    loop {
        // SAFETY: SYS_EXIT_EXTENDED (0x20) takes a pointer to a two-word parameter block.
        unsafe {
            cortex_m_semihosting::syscall(0x20, &block);
        }
    }
}

/// A host file opened through semihosting.
struct HostFile {
    handle: usize,
}

impl HostFile {
    /// Open `path` (bytes without NUL, at most 255) read-only binary.
    fn open(path: &[u8]) -> Result<Self, LogError> {
        let mut z = [0u8; 256];
        if path.len() >= z.len() {
            return Err(LogError::Open);
        }
        z[..path.len()].copy_from_slice(path);
        // SAFETY: OPEN takes (NUL-terminated name, mode, length without the NUL).
        let h = unsafe {
            cortex_m_semihosting::syscall(
                nr::OPEN,
                &[z.as_ptr() as usize, nr::open::R_BINARY, path.len()],
            )
        };
        if h == usize::MAX {
            Err(LogError::Open)
        } else {
            Ok(Self { handle: h })
        }
    }

    /// Read up to `buf.len()` bytes; returns how many were read (0 at end of file).
    fn read(&mut self, buf: &mut [u8]) -> Result<usize, LogError> {
        // SAFETY: READ takes (handle, buffer, length) and returns the bytes NOT read.
        let not_read = unsafe {
            cortex_m_semihosting::syscall(
                nr::READ,
                &[self.handle, buf.as_mut_ptr() as usize, buf.len()],
            )
        };
        if not_read > buf.len() {
            return Err(LogError::Io);
        }
        Ok(buf.len() - not_read)
    }
}

impl Drop for HostFile {
    fn drop(&mut self) {
        // SAFETY: CLOSE takes the handle.
        unsafe {
            cortex_m_semihosting::syscall(nr::CLOSE, &[self.handle]);
        }
    }
}

/// Buffered reader over a [`HostFile`].
struct Reader {
    file: HostFile,
    buf: [u8; 512],
    pos: usize,
    len: usize,
}

impl Reader {
    fn new(file: HostFile) -> Self {
        Self {
            file,
            buf: [0; 512],
            pos: 0,
            len: 0,
        }
    }

    /// Fill `out` entirely: `Ok(true)`; end of file before the first byte: `Ok(false)`;
    /// end of file inside: `Err(Truncated)`.
    fn read_exact(&mut self, out: &mut [u8]) -> Result<bool, LogError> {
        let mut done = 0;
        while done < out.len() {
            if self.pos == self.len {
                self.pos = 0;
                self.len = self.file.read(&mut self.buf)?;
                if self.len == 0 {
                    return if done == 0 {
                        Ok(false)
                    } else {
                        Err(LogError::Truncated)
                    };
                }
            }
            let n = (out.len() - done).min(self.len - self.pos);
            out[done..done + n].copy_from_slice(&self.buf[self.pos..self.pos + n]);
            self.pos += n;
            done += n;
        }
        Ok(true)
    }
}

/// The log path: the last word after the program name on the semihosting command line.
fn log_path(buf: &mut [u8; 256]) -> &[u8] {
    let mut block = [buf.as_mut_ptr() as usize, buf.len()];
    // SAFETY: GET_CMDLINE takes a pointer to (buffer, length) and writes the NUL-terminated
    // command line and its length.
    let r = unsafe { cortex_m_semihosting::syscall1(nr::GET_CMDLINE, block.as_mut_ptr() as usize) };
    // SAFETY: the host wrote the length through the pointer above.
    let len = unsafe { core::ptr::read_volatile(&block[1]) };
    if r != 0 || len > buf.len() {
        return DEFAULT_LOG.as_bytes();
    }
    // "<kernel path> <append>": the log name is the last word when there are at least two
    // (the host runner passes a name without spaces; the kernel path may contain some).
    let line = &buf[..len];
    let mut words = line
        .split(|&c| c == b' ' || c == 0)
        .filter(|w| !w.is_empty());
    let _program = words.next();
    words.next_back().unwrap_or(DEFAULT_LOG.as_bytes())
}

/// The first header field that differs from the compiled-in scene: (name, log, firmware).
/// Exact comparison: host-sim writes the scene's own f64 values.
fn scene_mismatch(h: &Header) -> Option<(&'static str, f64, f64)> {
    let (p, c) = (&h.params, &scene::STRUCTURE);
    [
        ("sample_rate_hz", h.sample_rate_hz, scene::SAMPLE_RATE_HZ),
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

/// Report the compiled-in scene, detector settings and model (`scene ...`, then `detector <Debug
/// form of the DetectorConfig>`, then `model ...`).
fn emit_scene() {
    defmt::info!(
        "scene rate_hz={=f64} ring={=u32} disp_range_m={=f32} path={=str}",
        scene::SAMPLE_RATE_HZ,
        scene::DETECTOR_RING as u32,
        scene::DISP_RANGE_M,
        scene::SCENE_PATH
    );
    defmt::info!("detector {=str}", scene::DETECTOR_DEBUG);
    model::emit();
}

/// Replay the log, run the benchmark, exit.
pub fn run() -> ! {
    let Some(cp) = cortex_m::Peripherals::take() else {
        defmt::error!("core peripherals already taken");
        exit(status::PERIPHERALS)
    };
    let painted = stack::paint();
    let mut ticks = bench::Ticks::new(cp.SYST);
    emit_scene();

    let estimator = match model::new() {
        Ok(e) => e,
        Err(e) => {
            defmt::error!(
                "the compiled-in structure or estimator is invalid: {=str}",
                e.param().name()
            );
            exit(status::STRUCTURE)
        }
    };
    let Ok(detector) = scene::Detector::new(scene::DETECTOR) else {
        defmt::error!("the detector rejected the compiled-in scene");
        exit(status::STRUCTURE)
    };

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
        .and_then(|()| sensor_log::parse_header(&hb))
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
    if let Some((field, log, fw)) = scene_mismatch(&header) {
        defmt::error!(
            "log header does not match the compiled-in scene: {=str} log={=f64} firmware={=f64} (rebuild with SSVR_SCENE)",
            field,
            log,
            fw
        );
        exit(status::SCENE_MISMATCH)
    }
    let source = if header.options & options::LOG_REVERSALS != 0 {
        EventSource::Samples
    } else {
        EventSource::Detector
    };

    let mut pipe = Pipeline::new(estimator, detector, source);
    let mut queue: Queue<FrameOut, QUEUE_LEN> = Queue::new();
    let (mut producer, mut consumer) = queue.split();
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
        let (mut sample, has_reversal) = sensor_log::parse_record(&rb);
        if has_reversal {
            let mut ev = [0u8; REVERSAL_LEN];
            match reader.read_exact(&mut ev) {
                Ok(true) => sample.reversal = Some(sensor_log::parse_reversal(&ev)),
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
            pipe.produce_batch(&batch, &mut producer);
            queued = 0;
            let _ = pipeline::drain(&mut consumer);
        }
    }
    pipe.produce_batch(batch.get(..queued).unwrap_or(&[]), &mut producer);
    let _ = pipeline::drain(&mut consumer);
    pipeline::emit_stats(&pipe.stats);
    model::emit_mu(model::mu_estimate(pipe.estimator()));
    if let Some(e) = read_error {
        defmt::error!("sensor log read failed after {=u32} samples: {}", n, e);
        exit(status::LOG_READ)
    }

    match (model::new(), scene::Detector::new(scene::DETECTOR)) {
        (Ok(e), Ok(d)) => bench::run(&mut ticks, e, d),
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
