//! Live calibration: what `gsens live` runs between its inputs and its screen.
//!
//! - the inputs as they arrive, from lines of `imu.csv`, `tracking.csv` or
//!   one merged stream ([`LineParser`], format in its module's docs), with
//!   every line that is not data reported as a [`Notice`] (garbage, out of
//!   order, a logger restarting), never dropped silently;
//! - a growing file read as it grows ([`Follower`], `tail -f`), surviving a
//!   partial last line and a file truncated by a restarting logger;
//! - a u-blox module's UBX stream, from a log being written or its serial
//!   port ([`Inputs::Ubx`], [`UbxOptions`]): its complete frames read as
//!   bytes arrive (`gsens_ublox::UbxStream`), the IMU its ESF messages or a
//!   growing IMU log, the batch estimate the loop-identifying
//!   `gsens_calib::calibrate_observations` and the final one that of the
//!   kept log (`received.ubx`) as `gsens report --ubx` makes it;
//! - the shaking seen by the IMU over the last seconds ([`MotionWindow`]:
//!   which axis, how hard, how fast);
//! - the one plain instruction for the person holding the board ([`instruct`]);
//! - the estimate at every epoch ([`StreamEstimate`], the batch path's least
//!   squares streamed on the channel average of each epoch);
//! - [`LiveSession`] accumulates the received data, schedules the batch
//!   estimate ([`BatchJob`], the same `gsens_calib::calibrate_logs` as
//!   `gsens estimate`, runnable in another thread) and answers a
//!   [`LiveView`] for the screen at any moment;
//! - [`Runtime`]: a whole session, from its inputs (read by one thread each:
//!   [`Source`], [`receive_monitor`]) to the final estimate on the logs it
//!   keeps, shown as plain lines or on a [`LiveScreen`]; wall time is read
//!   through a [`Clock`], so tests run it without waiting;
//! - a recorded session ([`read_session_dir`]) played back at real time or a
//!   multiple of it, as a merged stream or growing files ([`replay`]).
//!
//! The screen shows two estimates: the streamed one, new at every epoch, and
//! the batch pipeline's on the data received so far, with its checks, which
//! decides when the target is met. The final one is, by construction, the
//! batch estimate of the logs that `gsens live` keeps.
#![warn(missing_docs)]

mod choice;
mod clock;
mod follow;
mod guidance;
mod input;
mod kept;
mod merge;
mod monitor;
mod monitor_setup;
mod motion;
mod pacing;
mod plain;
mod recording;
mod replay;
mod runtime;
mod session;
mod sources;
mod stream;
mod ubx;

pub use choice::{InputChoice, InputChoiceError, LOOP_NOT_STATED};
pub use clock::{Clock, ManualClock, SystemClock};
pub use follow::Follower;
pub use guidance::{GENTLER_FRACTION, Instruction, LoopBand, Protocol, Situation, instruct};
pub use input::{
    Input, LineError, LineFormat, LineKind, LineParser, Notice, merged_header, merged_line, parse_imu_line,
};
pub use monitor::{Datagrams, MonitorInput, receive_monitor, record_monitor};
pub use monitor_setup::{MonitorSetup, NoticeLimit, monitor_setup, render_recorded_tracks};
pub use motion::{MotionWindow, Shaking};
pub use pacing::{CreateError, ReplaySink, SpeedError, check_speed, replay};
pub use recording::{MonitorRecording, RecordingError};
pub use replay::read_session_dir;
pub use runtime::{Display, Ending, Finished, Inputs, LiveScreen, Runtime, RuntimeConfig, RuntimeError};
pub use session::{
    AxisProgress, BatchJob, BatchOutcome, BatchResult, BatchVerdict, ChannelStatus, LiveConfig, LiveSession, LiveView,
    Pushed, UbxStatus,
};
pub use sources::{Source, SourceEvent};
pub use stream::{Epoch, EpochAverager, StreamEstimate};
pub use ubx::UbxOptions;
