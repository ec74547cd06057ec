use clap::Parser;
use shadowlab::cli::{Cli, run};
use std::io::Write;
use std::process::ExitCode;
use std::sync::Mutex;

/// The variable that turns off Mesa's device-select layer.
const NO_DEVICE_SELECT: &str = "NODEVICE_SELECT";

/// Writes log records to stderr and, when given, to a log file.
struct Tee(Option<Mutex<std::fs::File>>);

impl Write for Tee {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        if let Some(f) = &self.0 {
            f.lock().expect("log file lock").write_all(buf)?;
        }
        std::io::stderr().write_all(buf)?;
        Ok(buf.len())
    }
    fn flush(&mut self) -> std::io::Result<()> {
        std::io::stderr().flush()
    }
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    if !matches!(cli.command, shadowlab::cli::Command::View(_))
        && std::env::var_os(NO_DEVICE_SELECT).is_none()
    {
        // Mesa's device-select Vulkan layer probes the window system (and
        // prints an `error:` line when there is none) to rank the GPUs;
        // a command without a window has no use for it: shadowlab ranks
        // the adapters itself.
        // SAFETY: no other thread exists yet.
        unsafe { std::env::set_var(NO_DEVICE_SELECT, "1") };
    }
    let level = match cli.verbose {
        0 => "warn",
        1 => "info",
        _ => "debug",
    };
    let file = match &cli.log_file {
        Some(p) => match std::fs::File::create(p) {
            Ok(f) => Some(Mutex::new(f)),
            Err(e) => {
                eprintln!("error: cannot open log file {}: {e}", p.display());
                return ExitCode::from(2);
            }
        },
        None => None,
    };
    env_logger::Builder::from_env(
        env_logger::Env::default()
            .default_filter_or(format!("{level},wgpu_core=error,wgpu_hal=error,naga=warn")),
    )
    .target(env_logger::Target::Pipe(Box::new(Tee(file))))
    .init();
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            log::error!("{e:#}");
            if log::max_level() < log::LevelFilter::Error {
                eprintln!("error: {e:#}");
            }
            ExitCode::from(2)
        }
    }
}
