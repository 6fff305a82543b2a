//! `metamer devices`: serial ports and known USB/HID instruments on this machine, with the
//! fix for any the user may not open.

use metamer_drivers::devices::{list_devices, Access, DeviceList};
use metamer_drivers::registry;

use super::CliResult;

#[derive(clap::Args)]
pub struct Args {
    /// One JSON document instead of text.
    #[arg(long)]
    json: bool,
}

pub fn run(args: Args) -> CliResult {
    let list = list_devices();
    if args.json {
        outln!("{}", serde_json::to_string_pretty(&list)?)?;
    } else {
        out!("{}", human(&list))?;
    }
    Ok(())
}

fn access_text(a: &Access) -> String {
    match a {
        Access::Ok => String::new(),
        Access::Denied { fix } => format!("\n      {fix}"),
        Access::Unknown { why } => format!("\n      access not checked: {why}"),
    }
}

fn human(list: &DeviceList) -> String {
    let mut s = String::from("Serial ports (a CS-100A: --instrument cs100a:PORT):\n");
    if list.serial_ports.is_empty() {
        s.push_str("  none found\n");
    }
    for p in &list.serial_ports {
        s.push_str(&format!("  {}  {}", p.path, p.kind));
        if let Some(u) = &p.usb {
            s.push_str(&format!("  USB {:04x}:{:04x}", u.vid, u.pid));
            if let Some(serial) = &u.serial {
                s.push_str(&format!("  serial {serial}"));
            }
            let name: Vec<&str> = [u.manufacturer.as_deref(), u.product.as_deref()]
                .into_iter()
                .flatten()
                .collect();
            if !name.is_empty() {
                s.push_str(&format!("  ({})", name.join(" ")));
            }
        }
        if let Some(a) = p.adapter {
            s.push_str(&format!("  [{a} USB-serial adapter]"));
        }
        s.push_str(&access_text(&p.access));
        s.push('\n');
    }
    s.push_str("USB/HID instruments:\n");
    if list.instruments.is_empty() {
        s.push_str("  none found\n");
    }
    for d in &list.instruments {
        s.push_str(&format!(
            "  {}  {} {:04x}:{:04x}  {}",
            d.name, d.bus, d.vid, d.pid, d.location
        ));
        if let Some(serial) = &d.serial {
            s.push_str(&format!("  serial {serial}"));
        }
        if let Some(revision) = &d.revision {
            s.push_str(&format!("  {revision}"));
        }
        s.push_str(&access_text(&d.access));
        s.push('\n');
    }
    for note in &list.notes {
        s.push_str(&format!("note: {note}\n"));
    }
    s.push_str(&format!(
        "Simulated: {} (always available)\n",
        registry::simulated_specs().join(", ")
    ));
    s
}
