//! `metamer devices`: serial ports and known USB/HID instruments on this machine, with the
//! fix for any the user may not open; with `--describe MODEL`, what a model can do.

use metamer_drivers::describe::{describe, ModelDescription, DESCRIBED_CD_M2};
use metamer_drivers::devices::{list_devices, Access, DeviceList};
use metamer_drivers::{registry, CalibrationNeed, OptionValues};

use super::{CliError, CliResult};

#[derive(clap::Args)]
pub struct Args {
    /// One JSON document instead of text.
    #[arg(long)]
    json: bool,
    /// Instead of listing what is plugged in: what the model MODEL can do (cs100a, i1pro,
    /// …): how to name it, its modes with their calibrations and how long they last, its
    /// options and its stated repeatability.
    #[arg(long, value_name = "MODEL")]
    describe: Option<String>,
}

pub fn run(args: Args) -> CliResult {
    if let Some(model) = &args.describe {
        let d = describe(model).map_err(|e| match e {
            e @ metamer_drivers::DriverError::UnknownModel { .. } => {
                CliError::Usage(format!("--describe: {e}"))
            }
            e => CliError::from(e),
        })?;
        if args.json {
            outln!("{}", serde_json::to_string_pretty(&d)?)?;
        } else {
            out!("{}", described(&d))?;
        }
        return Ok(());
    }
    let list = list_devices();
    if args.json {
        outln!("{}", serde_json::to_string_pretty(&list)?)?;
    } else {
        out!("{}", human(&list))?;
    }
    Ok(())
}

/// A duration in the largest whole unit that fits: `30 min`, `1 h`, `45 s`.
fn lasting(s: f64) -> String {
    if s >= 3600.0 && s % 3600.0 == 0.0 {
        format!("{} h", s / 3600.0)
    } else if s >= 60.0 && s % 60.0 == 0.0 {
        format!("{} min", s / 60.0)
    } else {
        format!("{s} s")
    }
}

fn calibration(c: &CalibrationNeed) -> String {
    let valid = match c.valid_for_s {
        Some(s) => format!("valid {}", lasting(s)),
        None => "never expires within a session".into(),
    };
    format!("{} ({}; {valid})", c.name, c.condition.prompt())
}

fn described(d: &ModelDescription) -> String {
    let mut s = format!("{} ({})\n", d.title, d.name);
    if let Some(why) = d.unsupported {
        s.push_str(&format!("  not supported: {why}\n"));
    }
    let mut names = Vec::new();
    if let Some(real) = &d.real {
        names.push(format!("real {real}"));
    }
    if d.replay {
        names.push("replay:FILE.jsonl".into());
    }
    if let Some(sim) = &d.simulated {
        let mut options = vec!["time_scale", "seed", "noise"];
        options.extend(d.sim_options);
        names.push(format!("simulated {sim} (options: {})", options.join(", ")));
    }
    if !names.is_empty() {
        s.push_str(&format!("  named: {}\n", names.join("; ")));
    }
    for other in &d.other_names {
        s.push_str(&format!("  refused word {other}\n"));
    }
    if !d.usb.is_empty() {
        s.push_str(&format!("  USB: {}\n", d.usb.join(", ")));
    }
    for unit in &d.units {
        let c = &unit.capabilities;
        s.push_str(&format!(
            "  its driver on a simulated {} ({}):\n",
            unit.stands_for, unit.spec
        ));
        for m in &c.modes {
            let calibrations = if m.calibrations.is_empty() {
                "no calibration".to_string()
            } else {
                m.calibrations
                    .iter()
                    .map(calibration)
                    .collect::<Vec<_>>()
                    .join(", then ")
            };
            let how = if m.spot { "aimed" } else { "placed" };
            s.push_str(&format!("    {} ({how}): {calibrations}\n", m.mode));
        }
        for o in &c.options {
            let values = match &o.values {
                OptionValues::Choice(words) => words.join(" or "),
                OptionValues::Number {
                    min,
                    max,
                    unit,
                    auto,
                } => format!("{min}–{max} {unit}{}", if *auto { " or auto" } else { "" }),
            };
            s.push_str(&format!(
                "    option {}: {} ({values}; default {})\n",
                o.name, o.description, o.default
            ));
        }
        let mut facts = vec![if c.spectral { "spectral" } else { "XYZ only" }.to_string()];
        if let Some(angle) = c.acceptance_angle_deg {
            facts.push(format!("{angle}° acceptance"));
        }
        if let Some((low, high)) = c.luminance_range_cd_m2 {
            facts.push(format!("{low}–{high} cd/m²"));
        }
        s.push_str(&format!("    {}\n", facts.join(", ")));
        if !unit.times.is_empty() {
            let times: Vec<String> = unit
                .times
                .iter()
                .map(|t| {
                    format!(
                        "{} {:.3} s (calibration {:.3} s)",
                        t.mode, t.reading_s, t.calibration_s
                    )
                })
                .collect();
            s.push_str(&format!(
                "    one reading of {DESCRIBED_CD_M2} cd/m² (lx in ambient): {}\n",
                times.join(", ")
            ));
        }
    }
    if !d.repeatability.is_empty() {
        s.push_str("  stated repeatability (2σ of one reading):\n");
        for f in &d.repeatability {
            s.push_str(&format!("    {}: {} [{}]\n", f.mode, f.stated, f.source));
        }
    }
    if d.unsupported.is_none() && !d.time_budget_stated {
        s.push_str("  time budget: not stated by its driver yet\n");
    }
    s
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
