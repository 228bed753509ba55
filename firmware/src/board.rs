//! The Nucleo-F446RE image: ADS131M04 on SPI1, TIM2 interrupt at the sample rate, defmt over RTT.
//!
//! Wiring (Arduino header of the Nucleo):
//!
//! | ADS131M04 | STM32F446RE | Nucleo |
//! |-----------|-------------|--------|
//! | SCLK      | PA5 SPI1_SCK  | D13 |
//! | DOUT      | PA6 SPI1_MISO | D12 |
//! | DIN       | PA7 SPI1_MOSI | D11 |
//! | CS        | PB6 (GPIO)    | D10 |
//! | CLKIN     | 8.192 MHz oscillator on the ADC board | — |
//! | SYNC/RESET| pulled high   | — |
//!
//! Channels: AIN0 table accel, AIN1 base accel, AIN2 top accel, AIN3 base-to-table displacement.
//! The plan ([`crate::plan`]), the ADC configuration and the sensor scaling are made by build.rs
//! from the scene in `SSVR_SCENE` (default `scenes/board.toml`).
//!
//! TIM2 fires at the sample rate; its handler reads the latest ADC frame (the ADC's output data
//! rate is at least the sample rate), scales it and queues the raw sample. The main loop takes
//! whole batches of `ssvr_proto::BATCH` samples, runs the pipeline on them (detector, events,
//! model), streams the frames over RTT and sleeps.

/// Board-only consts of the scene (ADC, scaling, timer rate).
mod scene_board {
    include!(concat!(env!("OUT_DIR"), "/scene_board.rs"));
}

#[cfg(feature = "bench")]
use crate::bench;
use crate::{plan, stack, stream};
use ads131m04::Ads131m04;
use core::cell::RefCell;
use critical_section::Mutex;
use defmt_rtt as _;
use embedded_hal_bus::spi::{ExclusiveDevice, NoDelay};
use heapless::spsc::{Producer, Queue};
use ssvr_proto::{flags, Channel, EventSource, Frame, Sample, BATCH, CHANNELS};
use stm32f4xx_hal::gpio::{Output, PinState, PushPull, PB6};
use stm32f4xx_hal::pac::{self, interrupt, Interrupt, SPI1, TIM2};
use stm32f4xx_hal::prelude::*;
use stm32f4xx_hal::rcc::Config as RccConfig;
use stm32f4xx_hal::spi::{Mode, Phase, Polarity, Spi};
use stm32f4xx_hal::timer::{CounterHz, Event, Flag};

type AdcSpi = ExclusiveDevice<Spi<SPI1>, PB6<Output<PushPull>>, NoDelay>;
type Adc = Ads131m04<AdcSpi>;

/// Raw samples buffered between the sample interrupt and the main loop (a heapless queue of N
/// holds N − 1): the detector's fits at a stick take a few ms, during which the interrupt keeps
/// acquiring.
const RAW_QUEUE_LEN: usize = 64;

/// What the interrupt queues: the channels and flags of one sample (20 bytes; the board has no
/// log-provided reversals).
#[derive(Clone, Copy)]
struct RawSample {
    channels: [f32; CHANNELS],
    flags: u8,
}

/// Everything the sample interrupt owns: it only acquires and queues; the main loop runs the
/// detector and the estimator and streams the frames.
struct SampleSide {
    adc: Adc,
    timer: CounterHz<TIM2>,
    producer: Producer<'static, RawSample>,
    /// A sample was dropped (queue full): flag the next one that gets through.
    overrun: bool,
}

impl SampleSide {
    fn acquire(&mut self) -> Sample {
        match self.adc.read_si(&scene_board::CHANNEL_SCALES) {
            Ok((frame, si)) => {
                let sat = frame.saturation_mask();
                let mut f = 0;
                if sat != 0 {
                    f |= flags::SATURATED;
                }
                if sat & (1 << Channel::Displacement.index()) != 0 {
                    f |= flags::DISP_INVALID;
                }
                // Friction events come from the pipeline's detector.
                Sample {
                    channels: si,
                    flags: f,
                    reversal: None,
                }
            }
            Err(_) => Sample::missing(flags::ADC_ERROR),
        }
    }
}

/// The sample side, lent to the TIM2 handler. A reference (None = null) keeps this static in
/// `.bss`; the `SampleSide` itself lives in a `singleton!` (also zero-initialised RAM).
static SAMPLE_SIDE: Mutex<RefCell<Option<&'static mut SampleSide>>> =
    Mutex::new(RefCell::new(None));

/// Stop here (errors during start-up; no data path halts).
fn halt() -> ! {
    loop {
        cortex_m::asm::wfi();
    }
}

/// Start-up, then stream frames forever.
pub fn run() -> ! {
    let (Some(dp), Some(cp)) = (pac::Peripherals::take(), cortex_m::Peripherals::take()) else {
        defmt::error!("peripherals already taken");
        halt()
    };
    let painted = stack::paint();
    let plan = plan::PLAN;
    // `plan digest=.. model=.. rate_hz=.. ..`: the digest of the plan the image runs, for the host
    // to compare with its own plan of the scene and model.
    plan::emit();

    // 8 MHz HSE from the ST-LINK MCO (bypass), 180 MHz core.
    let mut rcc = dp.RCC.freeze(
        RccConfig::hse(8.MHz())
            .bypass_hse_oscillator()
            .sysclk(180.MHz()),
    );
    let gpioa = dp.GPIOA.split(&mut rcc);
    let gpiob = dp.GPIOB.split(&mut rcc);

    let spi = dp.SPI1.spi(
        (Some(gpioa.pa5), Some(gpioa.pa6), Some(gpioa.pa7)),
        Mode {
            polarity: Polarity::IdleLow,
            phase: Phase::CaptureOnSecondTransition,
        },
        8.MHz(),
        &mut rcc,
    );
    let cs = gpiob.pb6.into_push_pull_output_in_state(PinState::High);
    // Infallible: the chip-select pin cannot fail.
    let Ok(dev) = ExclusiveDevice::new_no_delay(spi, cs);
    let mut adc = Ads131m04::new(dev);
    let mut delay = dp.TIM5.delay_us(&mut rcc);
    if let Err(e) = adc.reset(&mut delay) {
        defmt::error!("ADS131M04 reset failed: {}", e.map_spi(|_| ()));
        halt()
    }
    if let Err(e) = adc.configure(&scene_board::ADC_CONFIG) {
        defmt::error!("ADS131M04 configuration failed: {}", e.map_spi(|_| ()));
        halt()
    }

    // Cost of the estimator and the detector in core clock cycles (SysTick on the core clock),
    // with feature `bench` only (a development build: 3–6 KB of flash).
    #[cfg(feature = "bench")]
    {
        let bench_plan = bench::plan_for(&plan);
        if let (Ok(m), Ok(d)) = (plan::model(&bench_plan), plan::detector(&bench_plan)) {
            let mut ticks = bench::Ticks::new(cp.SYST);
            bench::run(&mut ticks, &bench_plan, m, d);
        }
    }
    #[cfg(not(feature = "bench"))]
    let _ = cp;

    let Some(queue) = cortex_m::singleton!(: Queue<RawSample, RAW_QUEUE_LEN> = Queue::new()) else {
        halt()
    };
    let (producer, mut consumer) = queue.split();
    // In static RAM (counted in the image's RAM figure), owned by the main loop.
    // Not reachable (build.rs made the plan with the same code); no detail, to save flash.
    let Ok(pipe) = plan::pipeline(&plan, EventSource::Detector) else {
        defmt::error!("the compiled-in plan cannot run");
        halt()
    };
    let Some(pipeline) = cortex_m::singleton!(: plan::ImagePipeline = pipe) else {
        halt()
    };

    let mut timer = dp.TIM2.counter_hz(&mut rcc);
    if timer.start(scene_board::TIMER_RATE_HZ.Hz()).is_err() {
        defmt::error!("TIM2 cannot run at {=u32} Hz", scene_board::TIMER_RATE_HZ);
        halt()
    }
    timer.listen(Event::Update);
    let Some(side) = cortex_m::singleton!(: SampleSide = SampleSide {
        adc,
        timer,
        producer,
        overrun: false,
    }) else {
        halt()
    };
    critical_section::with(|cs| {
        SAMPLE_SIDE.borrow_ref_mut(cs).replace(side);
    });
    // SAFETY: the handler only touches SAMPLE_SIDE, initialised above.
    unsafe { cortex_m::peripheral::NVIC::unmask(Interrupt::TIM2) };

    let stats_every = scene_board::TIMER_RATE_HZ.saturating_mul(10).max(1);
    let mut streamed: u32 = 0;
    loop {
        let mut n: u32 = 0;
        // Whole batches of BATCH samples (the estimator's block; BATCH samples of latency).
        while consumer.len() >= BATCH {
            let mut batch = [Sample::missing(0); BATCH];
            for b in batch.iter_mut() {
                if let Some(raw) = consumer.dequeue() {
                    *b = Sample {
                        channels: raw.channels,
                        flags: raw.flags,
                        reversal: None,
                    };
                }
            }
            let mut frames = [Frame::EMPTY; BATCH];
            let done = pipeline.step_batch(&batch, &mut frames);
            for frame in frames.iter().take(done) {
                ssvr_proto::stream::emit_frame(frame);
            }
            n = n.wrapping_add(done as u32);
        }
        if n > 0 && streamed / stats_every != (streamed + n) / stats_every {
            ssvr_proto::stream::emit_stats(&pipeline.stats);
            stream::emit_mu(pipeline);
            stack::report(&painted);
        }
        streamed = streamed.wrapping_add(n);
        cortex_m::asm::wfi();
    }
}

#[interrupt]
fn TIM2() {
    critical_section::with(|cs| {
        if let Some(s) = SAMPLE_SIDE.borrow_ref_mut(cs).as_deref_mut() {
            s.timer.clear_flags(Flag::Update);
            let sample = s.acquire();
            let mut raw = RawSample {
                channels: sample.channels,
                flags: sample.flags,
            };
            if s.overrun {
                raw.flags |= flags::OVERRUN;
            }
            s.overrun = s.producer.enqueue(raw).is_err();
        }
    });
}

/// Log the panic over RTT and stop at a breakpoint (no data path can panic). The location is
/// not formatted: `PanicInfo::location` keeps every panic site's file name and the `core::fmt`
/// machinery in flash (~2.5 KB); `probe-rs run` prints the backtrace
/// when the core stops at the breakpoint.
#[panic_handler]
fn panic(_info: &core::panic::PanicInfo) -> ! {
    defmt::error!("panic (see the probe's backtrace)");
    loop {
        cortex_m::asm::bkpt();
    }
}
