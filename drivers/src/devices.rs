//! What is plugged in: serial ports (with their USB identity where the OS tells) and known
//! USB/HID colour instruments, each with whether this user may open it and, if not, how
//! to fix that. Works on a machine with no USB at all (an empty list, not an error).

use serde::Serialize;

use crate::permissions::SERIAL_PERMISSION_FIX;
pub use crate::permissions::USB_PERMISSION_FIX;
use crate::registry::{self, Bus};
use crate::DriverError;

/// Whether the current user may open a device.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
#[serde(tag = "access", rename_all = "snake_case")]
pub enum Access {
    /// Opening should work.
    Ok,
    /// The OS refuses; `fix` says what to do.
    Denied { fix: String },
    /// Not checked (e.g. the device could not be queried); `why` says so.
    Unknown { why: String },
}

/// USB identity of a port or device.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct UsbIds {
    pub vid: u16,
    pub pid: u16,
    pub serial: Option<String>,
    pub manufacturer: Option<String>,
    pub product: Option<String>,
}

/// A serial port.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct SerialPortEntry {
    pub path: String,
    /// `usb`, `pci`, `bluetooth` or `other`.
    pub kind: String,
    pub usb: Option<UsbIds>,
    /// The adapter chip when the VID:PID is a known USB-serial converter.
    pub adapter: Option<&'static str>,
    #[serde(flatten)]
    pub access: Access,
}

/// A known instrument on USB or HID.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct InstrumentEntry {
    pub name: &'static str,
    /// `usb` or `hid`.
    pub bus: &'static str,
    pub vid: u16,
    pub pid: u16,
    /// `bus 001 address 004` or the hidraw path.
    pub location: String,
    pub serial: Option<String>,
    /// Hardware revision where the descriptors tell it (an i1Pro: `Rev A–D` or `Rev E`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub revision: Option<String>,
    #[serde(flatten)]
    pub access: Access,
}

/// Everything `metamer devices` reports.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize)]
pub struct DeviceList {
    pub serial_ports: Vec<SerialPortEntry>,
    pub instruments: Vec<InstrumentEntry>,
    /// Things that could not be looked at (no USB on this machine, …).
    pub notes: Vec<String>,
}

/// Common USB-serial converters a CS-100A cable is plugged into (vendor datasheets).
pub const KNOWN_ADAPTERS: &[(u16, u16, &str)] = &[
    (0x0403, 0x6001, "FTDI FT232R"),
    (0x0403, 0x6015, "FTDI FT231X"),
    (0x067b, 0x2303, "Prolific PL2303"),
    (0x10c4, 0xea60, "Silicon Labs CP210x"),
    (0x1a86, 0x7523, "WCH CH340"),
];

/// Lists serial ports and known instruments.
///
/// # Examples
///
/// `metamer devices --json` as one call: what is plugged in, and for each port or
/// instrument whether this user may open it (with the fix when not).
///
/// ```
/// use metamer_drivers::devices::{list_devices, Access};
///
/// let list = list_devices();
/// for port in &list.serial_ports {
///     if let Access::Denied { fix } = &port.access {
///         println!("{}: {fix}", port.path);
///     }
/// }
/// let json = serde_json::to_value(&list)?;
/// assert!(json["serial_ports"].is_array() && json["instruments"].is_array());
/// # Ok::<(), serde_json::Error>(())
/// ```
pub fn list_devices() -> DeviceList {
    let mut list = DeviceList::default();
    match serialport::available_ports() {
        Ok(ports) => list.serial_ports = ports.into_iter().map(serial_entry).collect(),
        Err(e) => list
            .notes
            .push(format!("serial ports could not be listed: {e}")),
    }
    usb_instruments(&mut list);
    hid_instruments(&mut list);
    list
}

fn serial_entry(info: serialport::SerialPortInfo) -> SerialPortEntry {
    let (kind, usb) = match info.port_type {
        serialport::SerialPortType::UsbPort(u) => (
            "usb",
            Some(UsbIds {
                vid: u.vid,
                pid: u.pid,
                serial: u.serial_number,
                manufacturer: u.manufacturer,
                product: u.product,
            }),
        ),
        serialport::SerialPortType::PciPort => ("pci", None),
        serialport::SerialPortType::BluetoothPort => ("bluetooth", None),
        serialport::SerialPortType::Unknown => ("other", None),
    };
    let adapter = usb.as_ref().and_then(|u| {
        KNOWN_ADAPTERS
            .iter()
            .find(|(v, p, _)| *v == u.vid && *p == u.pid)
            .map(|(_, _, name)| *name)
    });
    let access = path_access(&info.port_name, SERIAL_PERMISSION_FIX);
    SerialPortEntry {
        path: info.port_name,
        kind: kind.into(),
        usb,
        adapter,
        access,
    }
}

/// Whether this process may read and write `path` (access(2): no side effects on the
/// device, unlike opening a tty, which can toggle DTR).
pub fn path_access(path: &str, fix: &str) -> Access {
    #[cfg(unix)]
    {
        let Ok(c) = std::ffi::CString::new(path) else {
            return Access::Unknown {
                why: "the path contains a NUL byte".into(),
            };
        };
        // SAFETY: `c` is a valid NUL-terminated string for the duration of the call.
        let r = unsafe { libc::access(c.as_ptr(), libc::R_OK | libc::W_OK) };
        if r == 0 {
            return Access::Ok;
        }
        access_from_error(&std::io::Error::last_os_error(), fix)
    }
    #[cfg(not(unix))]
    {
        let _ = (path, fix);
        Access::Unknown {
            why: "not checked on this OS".into(),
        }
    }
}

/// An OS error as an [`Access`]: permission problems carry their fix.
pub fn access_from_error(e: &std::io::Error, fix: &str) -> Access {
    if e.kind() == std::io::ErrorKind::PermissionDenied {
        Access::Denied {
            fix: format!("no permission to open it: {fix}"),
        }
    } else {
        Access::Unknown { why: e.to_string() }
    }
}

/// The title of the model with this ID on this bus, from the driver registry.
fn known(vid: u16, pid: u16, bus: Bus) -> Option<&'static str> {
    registry::by_usb(vid, pid, bus).map(|m| m.title)
}

fn usb_instruments(list: &mut DeviceList) {
    use rusb::UsbContext;
    // A private context: libusb's global one panics in rusb when there is no USB.
    let context = match rusb::Context::new() {
        Ok(c) => c,
        Err(e) => {
            list.notes.push(format!(
                "{}; no USB instruments listed",
                DriverError::usb_unavailable(&e)
            ));
            return;
        }
    };
    let devices = match context.devices() {
        Ok(d) => d,
        Err(e) => {
            list.notes
                .push(format!("USB devices could not be listed: {e}"));
            return;
        }
    };
    for device in devices.iter() {
        let Ok(desc) = device.device_descriptor() else {
            continue;
        };
        let Some(name) = known(desc.vendor_id(), desc.product_id(), Bus::Usb) else {
            continue;
        };
        let (access, serial) = match device.open() {
            Ok(handle) => {
                let serial = handle.read_serial_number_string_ascii(&desc).ok();
                (Access::Ok, serial)
            }
            Err(rusb::Error::Access) => (
                Access::Denied {
                    fix: format!("no permission to open it: {USB_PERMISSION_FIX}"),
                },
                None,
            ),
            Err(e) => (Access::Unknown { why: e.to_string() }, None),
        };
        list.instruments.push(InstrumentEntry {
            name,
            bus: Bus::Usb.name(),
            vid: desc.vendor_id(),
            pid: desc.product_id(),
            location: format!(
                "bus {:03} address {:03}",
                device.bus_number(),
                device.address()
            ),
            serial,
            revision: i1pro_revision(&device, &desc),
            access,
        });
    }
}

/// An i1Pro's revision from the endpoint count of its first configuration (the firmware,
/// which also decides, is only known once the driver has opened it).
fn i1pro_revision(
    device: &rusb::Device<rusb::Context>,
    desc: &rusb::DeviceDescriptor,
) -> Option<String> {
    let config = device.config_descriptor(0).ok()?;
    let endpoints = config
        .interfaces()
        .flat_map(|i| i.descriptors())
        .map(|d| usize::from(d.num_endpoints()))
        .sum();
    let model = metamer_protocols::i1pro::Model::detect(
        desc.vendor_id(),
        desc.product_id(),
        endpoints,
        None,
    )?;
    Some(match model.revision() {
        metamer_protocols::i1pro::Revision::AToD => "Rev A–D".into(),
        metamer_protocols::i1pro::Revision::E => "Rev E (i1Pro 2)".into(),
    })
}

fn hid_instruments(list: &mut DeviceList) {
    let api = match hidapi::HidApi::new() {
        Ok(a) => a,
        Err(e) => {
            list.notes
                .push(format!("HID devices could not be listed: {e}"));
            return;
        }
    };
    for info in api.device_list() {
        let Some(name) = known(info.vendor_id(), info.product_id(), Bus::Hid) else {
            continue;
        };
        let path = info.path().to_string_lossy().into_owned();
        list.instruments.push(InstrumentEntry {
            name,
            bus: Bus::Hid.name(),
            vid: info.vendor_id(),
            pid: info.product_id(),
            revision: None,
            access: path_access(&path, USB_PERMISSION_FIX),
            location: path,
            serial: info.serial_number().map(str::to_string),
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn listing_works_without_any_device() {
        // This machine (and CI) has no instruments and maybe no USB: no panic, no error.
        let list = list_devices();
        assert!(list.instruments.is_empty(), "{list:?}");
    }

    #[test]
    fn denied_access_carries_the_fix() {
        let e = std::io::Error::from_raw_os_error(13); // EACCES
        match access_from_error(&e, SERIAL_PERMISSION_FIX) {
            Access::Denied { fix } => {
                assert!(fix.contains("dialout") && fix.contains("udev"), "{fix}")
            }
            other => panic!("{other:?}"),
        }
        let json = serde_json::to_string(&Access::Denied { fix: "x".into() }).unwrap();
        assert_eq!(json, r#"{"access":"denied","fix":"x"}"#);
    }

    #[test]
    fn a_readable_file_is_accessible_and_a_missing_one_is_not_ok() {
        let dir = std::env::temp_dir().join(format!("metamer-access-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let f = dir.join("port");
        std::fs::write(&f, b"").unwrap();
        assert_eq!(path_access(f.to_str().unwrap(), "fix"), Access::Ok);
        assert!(matches!(
            path_access(dir.join("none").to_str().unwrap(), "fix"),
            Access::Unknown { .. }
        ));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn known_ids_are_matched_on_their_bus() {
        assert_eq!(
            known(0x0971, 0x2000, Bus::Usb),
            Some("X-Rite i1Pro / i1Pro 2")
        );
        assert_eq!(known(0x0971, 0x2000, Bus::Hid), None);
        assert_eq!(
            known(0x0765, 0x5020, Bus::Hid),
            Some("X-Rite i1Display Pro")
        );
    }
}

#[cfg(test)]
mod udev_tests {
    use super::*;

    /// Every device `metamer devices` knows is covered by the shipped udev rules, so the fix
    /// it prints works.
    #[test]
    fn the_udev_rules_cover_every_known_device() {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../data/udev/60-metamer.rules");
        let rules = std::fs::read_to_string(path).unwrap();
        let ids = registry::usb_ids()
            .map(|(_, id)| (id.vid, id.pid))
            .chain(KNOWN_ADAPTERS.iter().map(|(v, p, _)| (*v, *p)));
        for (vid, pid) in ids {
            let rule =
                format!(r#"ATTRS{{idVendor}}=="{vid:04x}", ATTRS{{idProduct}}=="{pid:04x}""#);
            assert!(rules.contains(&rule), "no rule for {vid:04x}:{pid:04x}");
        }
        assert!(USB_PERMISSION_FIX.contains("data/udev/60-metamer.rules"));
    }
}
