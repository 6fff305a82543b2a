//! Real USB (`rusb`, libusb built from source) and HID (`hidapi`) backends of [`UsbLink`]
//! and [`HidLink`], for the i1Pro driver. A private `rusb::Context` is used, never libusb's
//! global one, which panics in rusb on a machine without USB.

use std::time::Duration;

use metamer_protocols::transcript::TransferKind;

use super::usb::{ControlSetup, HidLink, UsbLink};
use super::LinkError;
use crate::DriverError;

/// A claimed interface of a USB device.
pub struct RusbLink {
    handle: rusb::DeviceHandle<rusb::Context>,
    name: String,
}

impl RusbLink {
    /// Opens the first device with `vid:pid` (and `serial`, when given) and claims
    /// `interface`.
    pub fn open(
        vid: u16,
        pid: u16,
        serial: Option<&str>,
        interface: u8,
    ) -> Result<RusbLink, DriverError> {
        use rusb::UsbContext;
        let name = format!("usb:{vid:04x}:{pid:04x}");
        let context = rusb::Context::new().map_err(|e| DriverError::usb_unavailable(&e))?;
        let devices = context
            .devices()
            .map_err(|e| DriverError::usb_unavailable(&e))?;
        let mut denied = false;
        for device in devices.iter() {
            let Ok(desc) = device.device_descriptor() else {
                continue;
            };
            if desc.vendor_id() != vid || desc.product_id() != pid {
                continue;
            }
            let handle = match device.open() {
                Ok(h) => h,
                Err(rusb::Error::Access) => {
                    denied = true;
                    continue;
                }
                Err(e) => return Err(usb_open_error(&name, e)),
            };
            if let Some(want) = serial {
                let got = handle.read_serial_number_string_ascii(&desc).ok();
                if got.as_deref() != Some(want) {
                    continue;
                }
            }
            // Linux binds some instruments to a kernel driver; detaching is not supported
            // everywhere, and where it is not, claiming reports the real problem.
            let _ = handle.set_auto_detach_kernel_driver(true);
            handle
                .claim_interface(interface)
                .map_err(|e| usb_open_error(&name, e))?;
            return Ok(RusbLink { handle, name });
        }
        if denied {
            return Err(DriverError::UsbPermission { device: name });
        }
        Err(DriverError::UsbNotFound {
            device: match serial {
                Some(s) => format!("{name} with serial {s}"),
                None => name,
            },
        })
    }

    fn err(&self, endpoint: u8, e: rusb::Error) -> LinkError {
        usb_link_error(&self.name, endpoint, e)
    }
}

fn usb_open_error(name: &str, e: rusb::Error) -> DriverError {
    match e {
        rusb::Error::Access => DriverError::UsbPermission {
            device: name.to_string(),
        },
        rusb::Error::Busy => DriverError::PortBusy {
            port: name.to_string(),
        },
        e => DriverError::UsbUnavailable {
            message: format!("{name}: {e}"),
        },
    }
}

fn usb_link_error(name: &str, endpoint: u8, e: rusb::Error) -> LinkError {
    match e {
        rusb::Error::Pipe => LinkError::Stalled { endpoint },
        rusb::Error::Timeout => LinkError::Timeout {
            timeout_ms: 0,
            received: Vec::new(),
        },
        rusb::Error::NoDevice => LinkError::Disconnected {
            received: Vec::new(),
        },
        e => LinkError::Io {
            port: name.to_string(),
            source: std::io::Error::other(e.to_string()),
        },
    }
}

impl UsbLink for RusbLink {
    fn control_in(
        &mut self,
        s: ControlSetup,
        len: usize,
        timeout: Duration,
    ) -> Result<Vec<u8>, LinkError> {
        let mut buf = vec![0u8; len];
        let n = self
            .handle
            .read_control(
                s.request_type,
                s.request,
                s.value,
                s.index,
                &mut buf,
                timeout,
            )
            .map_err(|e| self.err(0, e))?;
        buf.truncate(n);
        Ok(buf)
    }

    fn control_out(
        &mut self,
        s: ControlSetup,
        data: &[u8],
        timeout: Duration,
    ) -> Result<(), LinkError> {
        self.handle
            .write_control(s.request_type, s.request, s.value, s.index, data, timeout)
            .map(drop)
            .map_err(|e| self.err(0, e))
    }

    fn read(
        &mut self,
        kind: TransferKind,
        endpoint: u8,
        len: usize,
        timeout: Duration,
    ) -> Result<Vec<u8>, LinkError> {
        let mut buf = vec![0u8; len];
        let r = match kind {
            TransferKind::Bulk => self.handle.read_bulk(endpoint, &mut buf, timeout),
            TransferKind::Interrupt => self.handle.read_interrupt(endpoint, &mut buf, timeout),
        };
        let n = r.map_err(|e| self.err(endpoint, e))?;
        buf.truncate(n);
        Ok(buf)
    }

    fn write(
        &mut self,
        kind: TransferKind,
        endpoint: u8,
        data: &[u8],
        timeout: Duration,
    ) -> Result<(), LinkError> {
        let r = match kind {
            TransferKind::Bulk => self.handle.write_bulk(endpoint, data, timeout),
            TransferKind::Interrupt => self.handle.write_interrupt(endpoint, data, timeout),
        };
        match r.map_err(|e| self.err(endpoint, e))? {
            n if n == data.len() => Ok(()),
            n => Err(LinkError::Io {
                port: self.name.clone(),
                source: std::io::Error::other(format!("short write: {n} of {} bytes", data.len())),
            }),
        }
    }

    fn describe(&self) -> String {
        self.name.clone()
    }
}

/// An opened HID device.
pub struct HidapiLink {
    device: hidapi::HidDevice,
    name: String,
}

impl HidapiLink {
    /// Opens the first HID device with `vid:pid` (and `serial`, when given).
    pub fn open(vid: u16, pid: u16, serial: Option<&str>) -> Result<HidapiLink, DriverError> {
        let name = format!("hid:{vid:04x}:{pid:04x}");
        let api = hidapi::HidApi::new().map_err(|e| DriverError::UsbUnavailable {
            message: format!("HID: {e}"),
        })?;
        let Some(info) = api.device_list().find(|d| {
            d.vendor_id() == vid
                && d.product_id() == pid
                && serial.is_none_or(|s| d.serial_number() == Some(s))
        }) else {
            return Err(DriverError::UsbNotFound { device: name });
        };
        let path = info.path().to_string_lossy().into_owned();
        // Opening the hidraw node read-write has no side effects (unlike a tty's DTR) and
        // tells a permission problem apart from hidapi's opaque errors. Checked here rather
        // than with the device listing's helper, which would tie this link to the registry.
        if let Err(e) = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .open(&path)
        {
            if e.kind() == std::io::ErrorKind::PermissionDenied {
                return Err(DriverError::UsbPermission { device: name });
            }
        }
        let device = info
            .open_device(&api)
            .map_err(|e| DriverError::UsbUnavailable {
                message: format!("{name}: {e}"),
            })?;
        Ok(HidapiLink { device, name })
    }
}

impl HidLink for HidapiLink {
    fn write_report(&mut self, report: &[u8]) -> Result<(), LinkError> {
        self.device
            .write(report)
            .map(drop)
            .map_err(|e| LinkError::Io {
                port: self.name.clone(),
                source: std::io::Error::other(e.to_string()),
            })
    }

    fn read_report(&mut self, len: usize, timeout: Duration) -> Result<Vec<u8>, LinkError> {
        let mut buf = vec![0u8; len];
        let ms = i32::try_from(timeout.as_millis()).unwrap_or(i32::MAX);
        match self.device.read_timeout(&mut buf, ms) {
            Ok(0) => Err(LinkError::Timeout {
                timeout_ms: ms as u64,
                received: Vec::new(),
            }),
            Ok(n) => {
                buf.truncate(n);
                Ok(buf)
            }
            Err(e) => Err(LinkError::Io {
                port: self.name.clone(),
                source: std::io::Error::other(e.to_string()),
            }),
        }
    }

    fn describe(&self) -> String {
        self.name.clone()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// This machine and CI have no instruments (and maybe no USB at all): opening one is a
    /// clear error, never a panic.
    #[test]
    fn opening_an_absent_instrument_says_so() {
        for e in [
            RusbLink::open(0x0971, 0x2000, None, 0).err().unwrap(),
            HidapiLink::open(0x0765, 0x5020, None).err().unwrap(),
        ] {
            let msg = e.to_string();
            assert!(
                matches!(
                    e,
                    DriverError::UsbNotFound { .. } | DriverError::UsbUnavailable { .. }
                ),
                "{msg}"
            );
            assert!(
                msg.contains("metamer devices") || msg.contains("USB"),
                "{msg}"
            );
        }
    }

    #[test]
    fn permission_errors_carry_the_fix() {
        let msg = usb_open_error("usb:0971:2000", rusb::Error::Access).to_string();
        assert!(
            msg.contains("usb:0971:2000") && msg.contains("60-metamer.rules"),
            "{msg}"
        );
        assert!(matches!(
            usb_link_error("x", 0, rusb::Error::NoDevice),
            LinkError::Disconnected { .. }
        ));
        assert!(matches!(
            usb_link_error("x", 0, rusb::Error::Timeout),
            LinkError::Timeout { .. }
        ));
        assert!(matches!(
            usb_link_error("x", 0x82, rusb::Error::Pipe),
            LinkError::Stalled { endpoint: 0x82 }
        ));
    }
}
