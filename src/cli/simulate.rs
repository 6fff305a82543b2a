//! `metamer simulate cs100a --pty`: serves the simulated CS-100A on a pseudo-terminal for
//! other programs, until Ctrl-C or SIGTERM.

use clap::{Subcommand, ValueEnum};
use metamer::color::Xyz;
use metamer::rig::sim_meter::{PtyMeter, PtyMeterError, PtyMeterOptions};

use super::{parse_triple, CliError, CliResult};

#[derive(clap::Args)]
pub struct Args {
    #[command(subcommand)]
    device: Device,
}

#[derive(Subcommand)]
enum Device {
    /// The Konica Minolta CS-100A chroma meter (RS-232C protocol, 4800 baud 7E2).
    Cs100a(Cs100aArgs),
}

#[derive(Clone, Copy, ValueEnum)]
enum OnOff {
    On,
    Off,
}

#[derive(clap::Args)]
struct Cs100aArgs {
    /// Serve on a new pseudo-terminal; its path (/dev/pts/N) is the first line of output.
    #[arg(long)]
    pty: bool,
    /// The meter's repeatability noise (±0.2 % in Y, ±0.001 in x, y).
    #[arg(long, value_enum, default_value = "on")]
    noise: OnOff,
    /// Seed of the noise.
    #[arg(long, default_value_t = 1, value_name = "N")]
    seed: u64,
    /// Multiplies the meter's delays: 1 is the real pace (≈100 ms per reading), 0 none,
    /// at most 1000.
    #[arg(long, default_value_t = 1.0, value_name = "F")]
    time_scale: f64,
    /// The light the meter sees, cd/m² (default: 100 cd/m² of CIE LED-RGB1).
    #[arg(long, value_name = "X,Y,Z", value_parser = parse_triple)]
    xyz: Option<[f64; 3]>,
}

pub fn run(args: Args) -> CliResult {
    match args.device {
        Device::Cs100a(a) => cs100a(a),
    }
}

fn cs100a(args: Cs100aArgs) -> CliResult {
    if !args.pty {
        return Err(CliError::Usage(
            "say where to serve the meter: --pty (a new pseudo-terminal)".into(),
        ));
    }
    let defaults = PtyMeterOptions::default();
    let options = PtyMeterOptions {
        xyz: args.xyz.map(Xyz::from).unwrap_or(defaults.xyz),
        noise: matches!(args.noise, OnOff::On),
        seed: args.seed,
        time_scale: args.time_scale,
    };
    // Blocked before the emulator's thread starts, so that thread inherits the mask and
    // the signals wait for `sigwait` below instead of killing the process mid-reply.
    let signals = block_termination_signals()?;
    let meter = PtyMeter::start(&options).map_err(|e| match e {
        PtyMeterError::NotALight { .. } => CliError::Usage(format!("--xyz: {e}")),
        PtyMeterError::BadTimeScale(_) => CliError::Usage(format!("--time-scale: {e}")),
        e => CliError::from(e),
    })?;
    outln!("{}", meter.path())?;
    super::console::flush()?;
    errln!(
        "serving a simulated CS-100A on {} (4800 baud, 7E2); Ctrl-C stops",
        meter.path()
    )?;
    let signal = wait_for(&signals)?;
    errln!("stopped by signal {signal}")?;
    drop(meter);
    Ok(())
}

/// Blocks SIGINT and SIGTERM for this thread and the threads it starts; returns the set.
fn block_termination_signals() -> Result<libc::sigset_t, std::io::Error> {
    // SAFETY: sigset_t is plain data that sigemptyset initialises; the pointers are to
    // locals that outlive the calls.
    unsafe {
        let mut set: libc::sigset_t = std::mem::zeroed();
        libc::sigemptyset(&mut set);
        libc::sigaddset(&mut set, libc::SIGINT);
        libc::sigaddset(&mut set, libc::SIGTERM);
        let rc = libc::pthread_sigmask(libc::SIG_BLOCK, &set, std::ptr::null_mut());
        if rc != 0 {
            return Err(std::io::Error::from_raw_os_error(rc));
        }
        Ok(set)
    }
}

/// Waits until one of the blocked `signals` arrives; returns its number.
fn wait_for(signals: &libc::sigset_t) -> Result<i32, std::io::Error> {
    let mut signal = 0;
    // SAFETY: `signals` was initialised by block_termination_signals; `signal` is a local.
    let rc = unsafe { libc::sigwait(signals, &mut signal) };
    if rc != 0 {
        return Err(std::io::Error::from_raw_os_error(rc));
    }
    Ok(signal)
}
