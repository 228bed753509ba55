//! The queue between the log replay and the streaming loop: a batch's frames are queued
//! ([`FrameProducer::produce_batch`]); a full queue drops a frame and flags the next one that
//! gets through with `OVERRUN`.

use crate::plan::ImagePipeline;
use heapless::spsc::Producer;
use ssvr_proto::{flags, Frame, Sample, BATCH};

/// Capacity of the sample → streaming queue (a heapless queue of N holds N − 1 frames); the
/// QEMU replay drains it after every batch.
pub const QUEUE_LEN: usize = 64;

/// The producing side: the pipeline's frames into the queue.
pub struct FrameProducer<'a> {
    producer: Producer<'a, Frame>,
    overrun: bool,
}

impl<'a> FrameProducer<'a> {
    /// Around a queue's producer.
    pub fn new(producer: Producer<'a, Frame>) -> Self {
        Self {
            producer,
            overrun: false,
        }
    }

    /// Step the pipeline on a batch and queue its frames.
    pub fn produce_batch(&mut self, pipe: &mut ImagePipeline, samples: &[Sample]) {
        let mut frames = [Frame::EMPTY; BATCH];
        let n = pipe.step_batch(samples, &mut frames);
        for mut frame in frames.into_iter().take(n) {
            if self.overrun {
                frame.flags |= flags::OVERRUN;
            }
            match self.producer.enqueue(frame) {
                Ok(()) => self.overrun = false,
                Err(_) => {
                    self.overrun = true;
                    pipe.stats.dropped = pipe.stats.dropped.wrapping_add(1);
                }
            }
        }
    }
}
