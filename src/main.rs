//! gangue: the server (parse settings, start tracing, bind, serve, shut down gracefully), or a
//! sharded computation (`gangue compute`, `gangue merge`).

// As in lib.rs: no `unwrap`, `expect` or `panic!` in the server.
#![cfg_attr(
    not(test),
    deny(clippy::unwrap_used, clippy::expect_used, clippy::panic)
)]

use std::process::ExitCode;

use clap::Parser;
use gangue::config::{Cli, Command, Config};
use gangue::http::parts::HttpWire;

fn main() -> ExitCode {
    let cli = Cli::parse();
    match cli.command {
        None => serve(cli.config),
        Some(Command::Serve(config)) => serve(config),
        Some(Command::Compute(args)) => {
            solver_pool(&args.limits);
            match gangue::shard::compute(&args, &HttpWire) {
                Ok(path) => {
                    eprintln!("gangue: wrote {}", path.display());
                    ExitCode::SUCCESS
                }
                Err(e) => fail(e),
            }
        }
        Some(Command::Merge(args)) => {
            solver_pool(&args.limits);
            let stdout = std::io::stdout();
            let mut out = std::io::BufWriter::with_capacity(1 << 16, stdout.lock());
            match gangue::shard::merge(&args, &HttpWire, &mut out) {
                Ok(()) => ExitCode::SUCCESS,
                Err(e) => fail(e),
            }
        }
    }
}

/// The global thread pool of a command-line computation: `--solver-threads` threads.
fn solver_pool(config: &Config) {
    let _ = rayon::ThreadPoolBuilder::new()
        .num_threads(config.solver_threads())
        .build_global();
}

fn fail(e: gangue::shard::Failure) -> ExitCode {
    eprintln!("gangue: {}", e.message);
    if let Some(p) = e.problem {
        eprintln!("{p}");
    }
    ExitCode::from(1)
}

#[tokio::main]
async fn serve(config: Config) -> ExitCode {
    tracing_subscriber::fmt()
        .with_env_filter(
            tracing_subscriber::EnvFilter::try_from_default_env()
                .unwrap_or_else(|_| "info,tower_http=warn".into()),
        )
        .with_target(false)
        .with_ansi(std::io::IsTerminal::is_terminal(&std::io::stdout()))
        .init();
    if let Err(e) = config.validate() {
        eprintln!("gangue: {e}");
        return ExitCode::from(2);
    }
    let listener = match tokio::net::TcpListener::bind(config.bind).await {
        Ok(l) => l,
        Err(e) => {
            eprintln!("gangue: cannot bind {}: {e}", config.bind);
            return ExitCode::from(1);
        }
    };
    let addr = listener.local_addr().map_or(config.bind, |a| a);
    tracing::info!(%addr, "gangue listening: page at http://{addr}/, API docs at http://{addr}/docs");
    if let Err(e) = gangue::http::server::serve(listener, config, shutdown()).await {
        eprintln!("gangue: server error: {e}");
        return ExitCode::from(1);
    }
    ExitCode::SUCCESS
}

async fn shutdown() {
    let ctrl_c = async {
        let _ = tokio::signal::ctrl_c().await;
    };
    #[cfg(unix)]
    let term = async {
        if let Ok(mut s) = tokio::signal::unix::signal(tokio::signal::unix::SignalKind::terminate())
        {
            s.recv().await;
        }
    };
    #[cfg(not(unix))]
    let term = std::future::pending::<()>();
    tokio::select! {
        _ = ctrl_c => {},
        _ = term => {},
    }
    tracing::info!("shutting down");
}
