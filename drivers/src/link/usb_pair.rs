//! An in-process USB pair: a [`UsbLink`] host end whose transfers are answered by an
//! emulated device on its own thread, so a USB instrument's emulator sits behind the real
//! driver as the CS-100A emulator does behind its serial pair.
//!
//! The device answers each transfer with a [`TransferAnswer`]: data (after a delay it chooses, as
//! an instrument that is integrating), a stall, silence, or a disconnect. The host end
//! waits no longer than each transfer's timeout, as libusb does; a transfer the device
//! answers too late fails with [`LinkError::Timeout`] and its late answer is dropped, never
//! delivered to a later transfer. While the device is busy answering one transfer the next
//! waits, as on a real bus.

use std::sync::mpsc::{self, Receiver, RecvTimeoutError, Sender};
use std::thread::JoinHandle;
use std::time::Duration;

use metamer_protocols::transcript::TransferKind;

use super::usb::{ControlSetup, UsbLink};
use super::LinkError;

/// How an emulated device answers one transfer.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum TransferAnswer<T> {
    /// Completes at once with this result.
    Done(T),
    /// Completes with this result after the device has worked this long.
    After(Duration, T),
    /// The device stalls the endpoint: the host sees [`LinkError::Stalled`].
    Stall,
    /// The device does not answer: the host's transfer times out.
    Silent,
    /// The device goes away (unplugged, or it reset itself): this transfer and every later
    /// one fail with [`LinkError::Disconnected`].
    Disconnect,
}

impl<T> TransferAnswer<T> {
    fn map<U>(self, f: impl FnOnce(T) -> U) -> TransferAnswer<U> {
        match self {
            TransferAnswer::Done(t) => TransferAnswer::Done(f(t)),
            TransferAnswer::After(d, t) => TransferAnswer::After(d, f(t)),
            TransferAnswer::Stall => TransferAnswer::Stall,
            TransferAnswer::Silent => TransferAnswer::Silent,
            TransferAnswer::Disconnect => TransferAnswer::Disconnect,
        }
    }
}

/// A USB device emulated in-process. Each method answers one transfer from the host; the
/// emulator keeps whatever state its protocol needs between them.
pub trait UsbDevice: Send + 'static {
    /// A control transfer device → host asking for at most `len` bytes (more are cut, as
    /// the host's wLength limits what a device may send).
    fn control_in(&mut self, setup: ControlSetup, len: usize) -> TransferAnswer<Vec<u8>>;
    /// A control transfer host → device.
    fn control_out(&mut self, setup: ControlSetup, data: &[u8]) -> TransferAnswer<()>;
    /// A bulk or interrupt read of at most `len` bytes from IN endpoint `endpoint`.
    fn read(&mut self, kind: TransferKind, endpoint: u8, len: usize) -> TransferAnswer<Vec<u8>>;
    /// A bulk or interrupt write to OUT endpoint `endpoint`.
    fn write(&mut self, kind: TransferKind, endpoint: u8, data: &[u8]) -> TransferAnswer<()>;
}

/// One transfer on its way to the device.
enum Transfer {
    ControlIn(ControlSetup, usize),
    ControlOut(ControlSetup, Vec<u8>),
    Read(TransferKind, u8, usize),
    Write(TransferKind, u8, Vec<u8>),
}

/// What the device thread sends back for one transfer.
enum Outcome {
    Data(Vec<u8>),
    Stall,
    /// The device's code panicked on this transfer; the thread ends after sending it.
    Panicked(String),
}

type Request = (Transfer, Sender<Outcome>);

/// The host end: a [`UsbLink`] for the real driver.
pub struct UsbPairHost {
    /// None once the device is known to be gone.
    tx: Option<Sender<Request>>,
    name: String,
}

/// Starts `device` on its own thread and returns the host end; `name` is what messages call
/// the link (`sim:i1pro`). The thread ends when the host end is dropped or the device
/// disconnects, and the join handle gives the device back so a test can look at its state.
pub fn usb_pair<D: UsbDevice>(device: D, name: &str) -> (UsbPairHost, JoinHandle<D>) {
    let (tx, rx) = mpsc::channel();
    let thread = std::thread::Builder::new()
        .name(format!("usb-device {name}"))
        .spawn(move || serve(device, rx))
        .expect("spawning the USB device thread");
    (
        UsbPairHost {
            tx: Some(tx),
            name: name.to_string(),
        },
        thread,
    )
}

/// The device thread: one transfer at a time, in the order the host sent them.
fn serve<D: UsbDevice>(mut device: D, rx: Receiver<Request>) -> D {
    // The reply channel of a transfer left unanswered, held open so the host waits out its
    // timeout instead of seeing a closed channel. The host sends its next transfer only
    // after that timeout, so one is enough.
    let mut unanswered: Option<Sender<Outcome>> = None;
    while let Ok((transfer, reply)) = rx.recv() {
        unanswered = None;
        let answer = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| match transfer {
            Transfer::ControlIn(setup, len) => device.control_in(setup, len).map(|mut d| {
                d.truncate(len);
                d
            }),
            Transfer::ControlOut(setup, data) => {
                device.control_out(setup, &data).map(|()| Vec::new())
            }
            Transfer::Read(kind, endpoint, len) => device.read(kind, endpoint, len),
            Transfer::Write(kind, endpoint, data) => {
                device.write(kind, endpoint, &data).map(|()| Vec::new())
            }
        }));
        let answer = match answer {
            Ok(answer) => answer,
            Err(payload) => {
                let _ = reply.send(Outcome::Panicked(super::panic_message(payload.as_ref())));
                break;
            }
        };
        let outcome = match answer {
            TransferAnswer::Done(data) => Outcome::Data(data),
            TransferAnswer::After(delay, data) => {
                std::thread::sleep(delay);
                Outcome::Data(data)
            }
            TransferAnswer::Stall => Outcome::Stall,
            TransferAnswer::Silent => {
                unanswered = Some(reply);
                continue;
            }
            // Leaving drops both channels: this transfer and all later ones see a
            // disconnect.
            TransferAnswer::Disconnect => break,
        };
        // The host may have given up already (timeout); the answer is then dropped here.
        let _ = reply.send(outcome);
    }
    drop(unanswered);
    device
}

impl UsbPairHost {
    /// Sends one transfer and waits up to `timeout` for its outcome.
    fn transfer(
        &mut self,
        transfer: Transfer,
        endpoint: u8,
        timeout: Duration,
    ) -> Result<Vec<u8>, LinkError> {
        let disconnected = || LinkError::Disconnected {
            received: Vec::new(),
        };
        let tx = self.tx.as_ref().ok_or_else(disconnected)?;
        let (reply_tx, reply_rx) = mpsc::channel();
        if tx.send((transfer, reply_tx)).is_err() {
            self.tx = None;
            return Err(disconnected());
        }
        match reply_rx.recv_timeout(timeout) {
            Ok(Outcome::Data(data)) => Ok(data),
            Ok(Outcome::Stall) => Err(LinkError::Stalled { endpoint }),
            Ok(Outcome::Panicked(message)) => {
                self.tx = None;
                Err(LinkError::PeerPanicked {
                    link: self.name.clone(),
                    message,
                })
            }
            Err(RecvTimeoutError::Timeout) => Err(LinkError::Timeout {
                timeout_ms: timeout.as_millis() as u64,
                received: Vec::new(),
            }),
            // Silent answers keep their reply channel open, so a closed one means the
            // device thread has ended.
            Err(RecvTimeoutError::Disconnected) => {
                self.tx = None;
                Err(disconnected())
            }
        }
    }
}

impl UsbLink for UsbPairHost {
    fn control_in(
        &mut self,
        setup: ControlSetup,
        len: usize,
        timeout: Duration,
    ) -> Result<Vec<u8>, LinkError> {
        self.transfer(Transfer::ControlIn(setup, len), 0, timeout)
    }

    fn control_out(
        &mut self,
        setup: ControlSetup,
        data: &[u8],
        timeout: Duration,
    ) -> Result<(), LinkError> {
        self.transfer(Transfer::ControlOut(setup, data.to_vec()), 0, timeout)
            .map(drop)
    }

    fn read(
        &mut self,
        kind: TransferKind,
        endpoint: u8,
        len: usize,
        timeout: Duration,
    ) -> Result<Vec<u8>, LinkError> {
        let data = self.transfer(Transfer::Read(kind, endpoint, len), endpoint, timeout)?;
        if data.len() > len {
            // libusb reports LIBUSB_ERROR_OVERFLOW when a device sends more than was asked.
            return Err(LinkError::Io {
                port: self.name.clone(),
                source: std::io::Error::other(format!(
                    "overflow: the device sent {} bytes on endpoint 0x{endpoint:02x}, more \
                     than the {len} asked for",
                    data.len()
                )),
            });
        }
        Ok(data)
    }

    fn write(
        &mut self,
        kind: TransferKind,
        endpoint: u8,
        data: &[u8],
        timeout: Duration,
    ) -> Result<(), LinkError> {
        self.transfer(
            Transfer::Write(kind, endpoint, data.to_vec()),
            endpoint,
            timeout,
        )
        .map(drop)
    }

    fn describe(&self) -> String {
        self.name.clone()
    }
}

#[cfg(test)]
mod tests {
    use std::time::Instant;

    use super::*;

    const ECHO_STORE: u8 = 0x01;
    const ECHO_FETCH: u8 = 0x02;
    const TRIGGER: u8 = 0x10;
    const UNPLUG: u8 = 0xdd;
    const REFUSED: u8 = 0xff;
    const DATA_IN: u8 = 0x82;
    const WORK: Duration = Duration::from_millis(30);
    const LONG: Duration = Duration::from_millis(2000);

    /// A made-up device: control OUT 0x01 stores bytes that control IN 0x02 gives back;
    /// control OUT 0x10 starts a "measurement" whose 4 bytes the next bulk read of 0x82
    /// returns after 30 ms of work; a read with nothing started is never answered; request
    /// 0xFF and every bulk write stall; control OUT 0xDD unplugs it.
    #[derive(Default)]
    struct Toy {
        stored: Vec<u8>,
        triggered: bool,
        transfers: usize,
    }

    impl UsbDevice for Toy {
        fn control_in(&mut self, setup: ControlSetup, _len: usize) -> TransferAnswer<Vec<u8>> {
            self.transfers += 1;
            match setup.request {
                ECHO_FETCH => TransferAnswer::Done(self.stored.clone()),
                _ => TransferAnswer::Stall,
            }
        }

        fn control_out(&mut self, setup: ControlSetup, data: &[u8]) -> TransferAnswer<()> {
            self.transfers += 1;
            match setup.request {
                ECHO_STORE => {
                    self.stored = data.to_vec();
                    TransferAnswer::Done(())
                }
                TRIGGER => {
                    self.triggered = true;
                    TransferAnswer::Done(())
                }
                UNPLUG => TransferAnswer::Disconnect,
                _ => TransferAnswer::Stall,
            }
        }

        fn read(
            &mut self,
            _kind: TransferKind,
            endpoint: u8,
            _len: usize,
        ) -> TransferAnswer<Vec<u8>> {
            self.transfers += 1;
            if endpoint != DATA_IN || !self.triggered {
                return TransferAnswer::Silent;
            }
            self.triggered = false;
            TransferAnswer::After(WORK, vec![1, 2, 3, 4])
        }

        fn write(
            &mut self,
            _kind: TransferKind,
            _endpoint: u8,
            _data: &[u8],
        ) -> TransferAnswer<()> {
            self.transfers += 1;
            TransferAnswer::Stall
        }
    }

    fn setup(request: u8) -> ControlSetup {
        ControlSetup {
            request_type: 0x40,
            request,
            value: 0,
            index: 0,
        }
    }

    #[test]
    fn control_requests_echo_and_are_cut_to_the_asked_length() {
        let (mut host, device) = usb_pair(Toy::default(), "sim:toy");
        host.control_out(setup(ECHO_STORE), &[9, 8, 7], LONG)
            .unwrap();
        assert_eq!(
            host.control_in(setup(ECHO_FETCH), 64, LONG).unwrap(),
            vec![9, 8, 7]
        );
        assert_eq!(
            host.control_in(setup(ECHO_FETCH), 2, LONG).unwrap(),
            vec![9, 8]
        );
        assert_eq!(host.describe(), "sim:toy");
        drop(host);
        // The device thread ends with the host end and gives the device back.
        let toy = device.join().unwrap();
        assert_eq!((toy.stored, toy.transfers), (vec![9, 8, 7], 3));
    }

    #[test]
    fn a_bulk_read_is_answered_after_the_trigger_and_the_work() {
        let (mut host, _device) = usb_pair(Toy::default(), "sim:toy");
        let t = Instant::now();
        let e = host
            .read(TransferKind::Bulk, DATA_IN, 64, Duration::from_millis(40))
            .unwrap_err();
        assert!(
            matches!(e, LinkError::Timeout { timeout_ms: 40, .. }),
            "{e}"
        );
        assert!(t.elapsed() >= Duration::from_millis(40));
        host.control_out(setup(TRIGGER), &[], LONG).unwrap();
        let t = Instant::now();
        assert_eq!(
            host.read(TransferKind::Bulk, DATA_IN, 64, LONG).unwrap(),
            vec![1, 2, 3, 4]
        );
        assert!(t.elapsed() >= WORK, "{:?}", t.elapsed());
        // Too short a buffer for what the device sends is libusb's overflow.
        host.control_out(setup(TRIGGER), &[], LONG).unwrap();
        let e = host.read(TransferKind::Bulk, DATA_IN, 2, LONG).unwrap_err();
        assert!(
            e.to_string().contains("overflow: the device sent 4 bytes"),
            "{e}"
        );
    }

    #[test]
    fn an_answer_later_than_the_timeout_is_a_timeout_and_never_reaches_the_next_transfer() {
        let (mut host, _device) = usb_pair(Toy::default(), "sim:toy");
        host.control_out(setup(TRIGGER), &[], LONG).unwrap();
        let e = host
            .read(TransferKind::Bulk, DATA_IN, 64, Duration::from_millis(5))
            .unwrap_err();
        assert!(matches!(e, LinkError::Timeout { timeout_ms: 5, .. }), "{e}");
        // The late [1, 2, 3, 4] is dropped; the next transfer gets its own answer.
        host.control_out(setup(ECHO_STORE), &[5], LONG).unwrap();
        assert_eq!(
            host.control_in(setup(ECHO_FETCH), 8, LONG).unwrap(),
            vec![5]
        );
    }

    #[test]
    fn a_stall_names_the_endpoint_and_the_device_goes_on() {
        let (mut host, _device) = usb_pair(Toy::default(), "sim:toy");
        let e = host.control_out(setup(REFUSED), &[1], LONG).unwrap_err();
        assert!(matches!(e, LinkError::Stalled { endpoint: 0 }), "{e}");
        assert_eq!(
            e.to_string(),
            "the device stalled endpoint 0x00 (it refused the request)"
        );
        let e = host
            .write(TransferKind::Bulk, 0x01, &[1], LONG)
            .unwrap_err();
        assert!(matches!(e, LinkError::Stalled { endpoint: 0x01 }), "{e}");
        host.control_out(setup(ECHO_STORE), &[3], LONG).unwrap();
        assert_eq!(
            host.control_in(setup(ECHO_FETCH), 8, LONG).unwrap(),
            vec![3]
        );
    }

    #[test]
    fn after_a_disconnect_every_transfer_fails_at_once() {
        let (mut host, device) = usb_pair(Toy::default(), "sim:toy");
        let t = Instant::now();
        let e = host.control_out(setup(UNPLUG), &[], LONG).unwrap_err();
        assert!(matches!(e, LinkError::Disconnected { .. }), "{e}");
        let e = host.read(TransferKind::Bulk, DATA_IN, 8, LONG).unwrap_err();
        assert!(matches!(e, LinkError::Disconnected { .. }), "{e}");
        // Neither waited for its timeout.
        assert!(t.elapsed() < LONG, "{:?}", t.elapsed());
        assert_eq!(device.join().unwrap().transfers, 1);
    }

    #[test]
    fn a_recording_of_the_pair_replays_through_the_same_calls() {
        use crate::link::replay::Transcript;
        use crate::link::usb::{RecordUsb, ReplayUsb};
        let dir = std::env::temp_dir().join(format!("metamer-usbpair-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("toy.jsonl");
        let _ = std::fs::remove_file(&path);
        let (host, _device) = usb_pair(Toy::default(), "sim:toy");
        let mut rec = RecordUsb::create(host, &path, "toy", "usb", "toy session").unwrap();
        rec.control_out(setup(TRIGGER), &[], LONG).unwrap();
        assert_eq!(
            rec.read(TransferKind::Bulk, DATA_IN, 64, LONG).unwrap(),
            vec![1, 2, 3, 4]
        );
        drop(rec);
        let mut replay = ReplayUsb::new(Transcript::load(&path).unwrap()).unwrap();
        replay.control_out(setup(TRIGGER), &[], LONG).unwrap();
        assert_eq!(
            replay.read(TransferKind::Bulk, DATA_IN, 64, LONG).unwrap(),
            vec![1, 2, 3, 4]
        );
        replay.finish().unwrap();
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
