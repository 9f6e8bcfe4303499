//! Frame statistics: the frame rate, and the input-to-screen latency of tool commands (from the
//! UI thread handling the input to the frame that shows its effect being presented).

use std::collections::VecDeque;
use std::time::Instant;

use super::physics::Rates;

/// Frame rate and tool latency.
#[derive(Debug, Default)]
pub struct Stats {
    /// Frames drawn.
    pub frames: u64,
    /// Frames per second over the last report.
    pub fps: f64,
    clock: Option<(Instant, u64)>,
    /// Tool commands sent.
    pub tools_sent: u64,
    /// When each tool command still unseen on screen was sent.
    pending: VecDeque<(u64, Instant)>,
    /// (sum s, count, max s) since the last report.
    latency: (f64, u64, f64),
    /// The last report: mean and max latency, s.
    pub latency_shown: (f64, f64),
}

impl Stats {
    /// A tool command was sent now.
    pub fn sent(&mut self) {
        self.tools_sent += 1;
        if self.pending.len() < 256 {
            self.pending.push_back((self.tools_sent, Instant::now()));
        }
    }

    /// A frame showing the effect of the first `applied` tool commands was presented.
    pub fn shown(&mut self, applied: u64) {
        while let Some(&(seq, sent)) = self.pending.front() {
            if seq > applied {
                break;
            }
            let l = sent.elapsed().as_secs_f64();
            self.latency = (self.latency.0 + l, self.latency.1 + 1, self.latency.2.max(l));
            self.pending.pop_front();
        }
    }

    /// Counts a frame; once a second updates the reports (and prints them when `print`).
    pub fn count_frame(&mut self, print: bool, rates: Rates) {
        self.frames += 1;
        let (since, count) = *self.clock.get_or_insert((Instant::now(), 0));
        if since.elapsed().as_secs_f64() < 1.0 {
            return;
        }
        self.fps = (self.frames - count) as f64 / since.elapsed().as_secs_f64();
        self.clock = Some((Instant::now(), self.frames));
        if self.latency.1 > 0 {
            self.latency_shown = (self.latency.0 / self.latency.1 as f64, self.latency.2);
            self.latency = (0.0, 0, 0.0);
        }
        if print {
            eprintln!(
                "fps {:.1}, physics {:.0} ticks/s, {:.1} us/step, tool latency mean {:.1} ms max {:.1} ms",
                self.fps,
                rates.ticks_per_s,
                rates.step_us,
                self.latency_shown.0 * 1e3,
                self.latency_shown.1 * 1e3
            );
        }
    }
}
