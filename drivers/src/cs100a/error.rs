//! What can go wrong talking to a CS-100A, in words that tell the user what to do at the
//! meter. Every message names the port and the command, so a log line stands alone.

use metamer_protocols::cs100a::{ReplyError, Status};

/// A CS-100A failure; [`DriverError`](crate::DriverError) wraps it unchanged.
#[derive(Debug, thiserror::Error)]
pub enum Cs100aError {
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
    /// A reply that is not CS-100A protocol.
    #[error("the CS-100A on {port} answered '{command}' with {received}, which is not a valid reply: {reason}")]
    BadReply {
        port: String,
        command: String,
        received: String,
        #[source]
        reason: ReplyError,
    },
    /// A reply that is valid protocol but carries values no meter can have measured.
    #[error("the CS-100A on {port} answered '{command}' with {received}, an impossible reading: {reason}")]
    ImpossibleReading {
        port: String,
        command: String,
        received: String,
        #[source]
        reason: metamer_color::Implausible,
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
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::DriverError;

    #[test]
    fn the_common_error_shows_the_meter_message_unchanged() {
        let inner = Cs100aError::NotInRemoteMode {
            port: "/dev/ttyUSB0".into(),
            command: "MDS,04".into(),
            timeout_ms: 5000,
        };
        let text = inner.to_string();
        assert!(text.starts_with(
            "the CS-100A on /dev/ttyUSB0 did not answer 'MDS,04' within 5000 ms: it is not in \
             remote mode. Switch the meter off, then hold F"
        ));
        let e: DriverError = inner.into();
        assert_eq!(e.to_string(), text);
        assert!(matches!(
            e,
            DriverError::Cs100a(Cs100aError::NotInRemoteMode {
                timeout_ms: 5000,
                ..
            })
        ));
        let refused: DriverError = Cs100aError::Instrument {
            port: "sim".into(),
            command: "MES".into(),
            status: Status::Er10,
        }
        .into();
        assert!(refused
            .to_string()
            .starts_with("the CS-100A on sim answered 'MES' with ER10"));
    }
}
