//! Live calibration: what `gsens live` runs between its inputs and its screen.
//!
//! - [`input`]: the inputs as they arrive, from lines of `imu.csv`,
//!   `tracking.csv` or one merged stream ([`input::parse_merged_line`],
//!   format in its docs), with every line that is not data reported as a
//!   [`Notice`] (garbage, out of order, a logger restarting), never dropped
//!   silently;
//! - [`follow`]: a growing file read as it grows (`tail -f`), surviving a
//!   partial last line and a file truncated by a restarting logger;
//! - [`motion`]: the shaking seen by the IMU over the last seconds (which
//!   axis, how hard, how fast);
//! - [`guidance`]: the one plain instruction for the person holding the board;
//! - [`stream`]: the estimate at every epoch ([`StreamEstimate`], the batch
//!   path's least squares streamed on the channel average of each epoch);
//! - [`session`]: [`LiveSession`] accumulates the received data, schedules the
//!   batch estimate ([`BatchJob`], the same `gsens_calib::calibrate_logs` as
//!   `gsens estimate`, runnable in another thread) and answers a
//!   [`LiveView`] for the screen at any moment;
//! - [`runtime`]: a whole session, from its inputs (read by one thread each,
//!   [`sources`], [`monitor`]) to the final estimate on the logs it keeps,
//!   shown as plain lines or on a [`LiveScreen`]; wall time is read through
//!   a [`Clock`], so tests run it without waiting;
//! - [`pacing`]: a recorded session ([`read_session_dir`]) played back at
//!   real time or a multiple of it, as a merged stream or growing files.
//!
//! The screen shows two estimates: the streamed one, new at every epoch, and
//! the batch pipeline's on the data received so far, with its checks, which
//! decides when the target is met. The final one is, by construction, the
//! batch estimate of the logs that `gsens live` keeps.
#![warn(missing_docs)]

pub mod clock;
pub mod follow;
pub mod guidance;
pub mod input;
mod kept;
mod merge;
pub mod monitor;
pub mod monitor_setup;
pub mod motion;
pub mod pacing;
mod plain;
pub mod replay;
pub mod runtime;
pub mod session;
pub mod sources;
pub mod stream;
pub mod truth;

pub use clock::{Clock, ManualClock, SystemClock};
pub use follow::Follower;
pub use gsens_calib::{Warning, WarningCode};
pub use guidance::{Instruction, LoopBand, Protocol};
pub use input::{
    Input, LineError, LineKind, Notice, merged_line, parse_imu_line, parse_merged_line, parse_tracking_line,
};
pub use monitor::{Datagrams, MonitorInput, receive_monitor, record_monitor};
pub use monitor_setup::{MonitorSetup, NoticeLimit, monitor_setup, render_recorded_tracks};
pub use motion::{MotionWindow, Shaking};
pub use pacing::{CreateError, ReplaySink, replay};
pub use replay::read_session_dir;
pub use runtime::{Display, Ending, Finished, Inputs, LiveScreen, Runtime, RuntimeConfig, RuntimeError};
pub use session::{AxisProgress, BatchJob, BatchResult, ChannelStatus, LiveConfig, LiveSession, LiveView, Pushed};
pub use sources::{LineFormat, Source, SourceEvent};
pub use stream::{Epoch, EpochAverager, StreamEstimate};
pub use truth::{TruthLoopUse, settings_of_simulated_session, take_truth_loop};
