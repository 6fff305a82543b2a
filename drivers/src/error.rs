//! Errors of links and drivers, each with the context a user needs to act on it.

use metamer_protocols::cs100a::{ReplyError, Status};

use crate::link::LinkError;

/// How to get access to a serial port on Linux, said wherever access is denied.
pub const SERIAL_PERMISSION_FIX: &str = "add yourself to the group that owns the port \
     (usually 'dialout': sudo usermod -aG dialout $USER, then log out and in again) or install \
     data/udev/60-metamer.rules (see README, 'Linux permissions')";

/// What went wrong talking to an instrument.
#[derive(Debug, thiserror::Error)]
pub enum DriverError {
    /// The instrument spec string is not understood.
    #[error("unknown instrument '{spec}': expected cs100a:PORT, replay:FILE.jsonl or sim:cs100a")]
    UnknownSpec { spec: String },
    /// An option of a spec (`sim:cs100a?time_scale=…`) is not understood.
    #[error("instrument '{spec}': {message}")]
    BadSpecOption { spec: String, message: String },
    /// The port does not exist.
    #[error(
        "serial port {port} does not exist; `metamer devices` lists the ports of this machine"
    )]
    PortNotFound { port: String },
    /// The user may not open the port.
    #[error("no permission to open serial port {port}: {SERIAL_PERMISSION_FIX}")]
    PortPermission { port: String },
    /// Another program holds the port.
    #[error("serial port {port} is in use by another program (close it, or find it with `fuser {port}`)")]
    PortBusy { port: String },
    /// Any other failure to open or configure the port.
    #[error("cannot open serial port {port}: {message}")]
    PortOpen { port: String, message: String },
    /// The CS-100A sent nothing: it is not in remote mode (PP docstring; [C2]).
    #[error(
        "the CS-100A on {port} did not answer '{command}' within {timeout_ms} ms: it is not in \
         remote mode. Switch the meter off, then hold F while switching it on until a 'C' shows \
         at the bottom right of its display (this is needed after every power cycle); also check \
         the cable and that the meter is on"
    )]
    NotInRemoteMode {
        port: String,
        command: String,
        timeout_ms: u64,
    },
    /// The meter answered earlier in this session, then went silent: switched off (which
    /// also ends remote mode), batteries out, or the cable came loose.
    #[error(
        "the CS-100A on {port} stopped answering: no reply to '{command}' within {timeout_ms} ms. \
         If it was switched off or its batteries ran out, switch it on again while holding F \
         until a 'C' shows at the bottom right of its display (remote mode); also check the cable"
    )]
    StoppedAnswering {
        port: String,
        command: String,
        timeout_ms: u64,
    },
    /// Part of a reply came, then silence.
    #[error(
        "the CS-100A on {port} stopped in the middle of its reply to '{command}': received {received} \
         and then nothing for {timeout_ms} ms; check the cable and the meter's batteries"
    )]
    PartialReply {
        port: String,
        command: String,
        received: String,
        timeout_ms: u64,
    },
    /// The device went away during an exchange.
    #[error(
        "the instrument on {port} disconnected during '{command}' (received {received}); \
         reconnect the cable and try again"
    )]
    Disconnected {
        port: String,
        command: String,
        received: String,
    },
    /// A reply that is not CS-100A protocol.
    #[error("the CS-100A on {port} answered '{command}' with {received}, which is not a valid reply: {reason}")]
    BadReply {
        port: String,
        command: String,
        received: String,
        #[source]
        reason: ReplyError,
    },
    /// A reply that is valid protocol but not an answer to the command sent (e.g. bare OK00
    /// to MES).
    #[error("the CS-100A on {port} answered '{command}' with {received}: {reason}")]
    UnexpectedReply {
        port: String,
        command: String,
        received: String,
        reason: String,
    },
    /// The meter reported an error code.
    #[error("the CS-100A on {port} answered '{command}' with {status}")]
    Instrument {
        port: String,
        command: String,
        status: Status,
    },
    /// A link failure not covered above (I/O error, replay mismatch).
    #[error("{0}")]
    Link(#[from] LinkError),
    /// A transcript could not be read.
    #[error("transcript {file} line {line}: {message}")]
    Transcript {
        file: String,
        line: usize,
        message: String,
    },
    /// A file (transcript to replay or record) could not be opened.
    #[error("cannot open {file}: {source}")]
    File {
        file: String,
        #[source]
        source: std::io::Error,
    },
    /// USB (or HID) cannot be used on this machine.
    #[error("USB is not available: {message}")]
    UsbUnavailable { message: String },
    /// No such USB/HID device is plugged in.
    #[error("no {device} is plugged in; `metamer devices` lists the instruments of this machine")]
    UsbNotFound { device: String },
    /// The user may not open the USB/HID device.
    #[error(
        "no permission to open {device}: {}",
        crate::devices::USB_PERMISSION_FIX
    )]
    UsbPermission { device: String },
    /// The instrument cannot do what was asked.
    #[error("the {instrument} cannot do {what}")]
    Unsupported { instrument: String, what: String },
    /// A model-specific setting the instrument does not have.
    #[error("the {instrument} has no option '{option}' (known: {known})")]
    UnknownOption {
        instrument: String,
        option: String,
        known: String,
    },
    /// A model-specific setting given a value it does not take.
    #[error("the {instrument}'s option {option}={value:?}: {message}")]
    BadOption {
        instrument: String,
        option: String,
        value: String,
        message: String,
    },
    /// A calibration is due (never done, or expired) before the instrument can measure in
    /// this mode; negotiate it with `calibration_needed`/`calibrate` and measure again.
    #[error("the {instrument} must be calibrated for {mode} measurements first ({reason}): {}", condition.prompt())]
    NeedsCalibration {
        instrument: String,
        mode: crate::instrument::MeasureMode,
        condition: crate::instrument::CalibrationCondition,
        reason: String,
    },
    /// The simulated instrument could not be started.
    #[error("simulated instrument: {0}")]
    Simulation(String),
}
