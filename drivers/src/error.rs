//! Errors of links and drivers, each with the context a user needs to act on it.

use crate::link::LinkError;
use crate::permissions::{SERIAL_PERMISSION_FIX, USB_PERMISSION_FIX};

/// What went wrong talking to an instrument.
#[derive(Debug, thiserror::Error)]
pub enum DriverError {
    /// The instrument spec string is not understood; `expected` lists the forms the driver
    /// registry knows.
    #[error("unknown instrument '{spec}': expected {expected}")]
    UnknownSpec { spec: String, expected: String },

    /// The spec names a model by a word it is not opened by (`i1pro2`), or one metamer
    /// does not drive (`i1pro3`); `message` says how to name it, or why it is not
    /// supported.
    #[error("instrument '{spec}': {message}")]
    NamedOtherwise { spec: String, message: String },

    /// No model of the registry has this name.
    #[error("no instrument model is named '{name}' (known: {known})")]
    UnknownModel { name: String, known: String },

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
    /// A CS-100A failure (not in remote mode, silent, garbled or refusing).
    #[error(transparent)]
    Cs100a(#[from] crate::cs100a::error::Cs100aError),
    /// An i1Pro failure (EEPROM, readings, too bright or too dark, a failed transfer).
    #[error(transparent)]
    I1Pro(#[from] crate::i1pro::I1ProError),
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
    /// USB (or HID) cannot be used on this machine; `message` says why in the machine's
    /// terms ([`DriverError::usb_unavailable`]).
    #[error("USB is not available on this machine: {message}")]
    UsbUnavailable { message: String },
    /// No such USB/HID device is plugged in.
    #[error("no {device} is plugged in; `metamer devices` lists the instruments of this machine")]
    UsbNotFound { device: String },
    /// The user may not open the USB/HID device.
    #[error("no permission to open {device}: {USB_PERMISSION_FIX}")]
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
        mode: crate::mode::MeasureMode,
        condition: crate::mode::CalibrationCondition,
        reason: String,
    },
    /// The simulated instrument could not be started.
    #[error("simulated instrument: {0}")]
    Simulation(String),
}

/// Where Linux's libusb looks for USB devices.
const USBFS: &str = "/dev/bus/usb";

impl DriverError {
    /// libusb could not start: the one error every command gives (and `metamer devices`
    /// notes) when USB is out of reach.
    pub fn usb_unavailable(e: &rusb::Error) -> DriverError {
        DriverError::UsbUnavailable {
            message: usb_unavailable_reason(e, std::path::Path::new(USBFS)),
        }
    }

    /// Whether the spec itself is wrong (an unknown form, a model named by another word or
    /// not driven, a bad option), as opposed to something that failed while opening what it
    /// names.
    pub fn is_spec(&self) -> bool {
        matches!(
            self,
            DriverError::UnknownSpec { .. }
                | DriverError::NamedOtherwise { .. }
                | DriverError::BadSpecOption { .. }
        )
    }
}

/// Why libusb could not start, in the machine's terms: libusb reports a missing device
/// filesystem as its catch-all "Other error", which tells the user nothing.
fn usb_unavailable_reason(e: &rusb::Error, usbfs: &std::path::Path) -> String {
    if cfg!(target_os = "linux") && !usbfs.exists() {
        return format!(
            "{} does not exist (no USB controller, or a container or sandbox started without \
             the host's USB devices; libusb said: {e})",
            usbfs.display()
        );
    }
    match e {
        rusb::Error::Access => format!("no permission to read {} ({e})", usbfs.display()),
        rusb::Error::NoMem => "libusb ran out of memory while starting".into(),
        rusb::Error::NotSupported => "libusb does not support USB on this system".into(),
        other => format!("libusb could not start ({other})"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn libusbs_other_error_is_explained_by_the_missing_device_filesystem() {
        let missing = std::path::Path::new("/nonexistent/bus/usb");
        let why = usb_unavailable_reason(&rusb::Error::Other, missing);
        if cfg!(target_os = "linux") {
            assert_eq!(
                why,
                "/nonexistent/bus/usb does not exist (no USB controller, or a container or \
                 sandbox started without the host's USB devices; libusb said: Other error)"
            );
        }
        let present = std::env::temp_dir();
        let why = usb_unavailable_reason(&rusb::Error::Access, &present);
        assert!(why.starts_with("no permission to read"), "{why}");
    }
}
