//! `ricochet run … --live`: the run served over Foxglove's WebSocket protocol as it goes
//! (crate feature `live`; see `ricochet::log::LiveView`).

use ricochet::log::Tap;
use ricochet::math::Real;

/// The live view options of `ricochet run`.
#[derive(clap::Args)]
pub struct LiveArgs {
    /// Serve the run live over Foxglove's WebSocket protocol while it runs (in Foxglove:
    /// Open connection → Foxglove WebSocket); the log is still written. Needs a ricochet
    /// built with `--features live`.
    #[arg(long)]
    live: bool,
    /// With --live: simulated seconds per wall-clock second.
    #[arg(
        long,
        requires = "live",
        allow_negative_numbers = true,
        default_value_t = 1.0
    )]
    speed: Real,
    /// With --live: the TCP port (0: any free port).
    #[arg(long, requires = "live", default_value_t = 8765)]
    port: u16,
    /// With --live: the address to listen on (the default serves this machine only).
    #[arg(long, requires = "live", default_value = "127.0.0.1")]
    host: String,
    /// With --live: seconds to keep serving after the run, so that the last messages reach
    /// the viewer.
    #[arg(
        long,
        requires = "live",
        allow_negative_numbers = true,
        default_value_t = 1.0
    )]
    linger: Real,
}

/// The live view asked for, started, or `None`. Start it before the log is created, so
/// that a port in use leaves no file behind.
pub fn start(args: &LiveArgs) -> anyhow::Result<Option<Box<dyn Tap>>> {
    if !args.live {
        return Ok(None);
    }
    serve(args).map(Some)
}

#[cfg(feature = "live")]
fn serve(args: &LiveArgs) -> anyhow::Result<Box<dyn Tap>> {
    use std::io::Write;
    let linger = std::time::Duration::try_from_secs_f64(args.linger).map_err(|_| {
        anyhow::anyhow!(
            "--linger must be a non-negative number of seconds, not {}",
            args.linger
        )
    })?;
    let options = ricochet::log::LiveOptions {
        host: args.host.clone(),
        port: args.port,
        speed: args.speed,
        linger,
    };
    let view = ricochet::log::LiveView::start(&options)?;
    let mut err = std::io::stderr().lock();
    writeln!(
        err,
        "live: ws://{}:{} at {}× real time — in Foxglove: Open connection → Foxglove WebSocket",
        args.host,
        view.port(),
        args.speed
    )?;
    err.flush()?;
    Ok(Box::new(view))
}

#[cfg(not(feature = "live"))]
fn serve(_: &LiveArgs) -> anyhow::Result<Box<dyn Tap>> {
    anyhow::bail!(
        "this ricochet was built without live view; rebuild with \
         `cargo build --release --features live`"
    )
}
