//! The `tissue-sim` binary: a thin wrapper around [`tissue_sim::cli`].

fn main() -> std::process::ExitCode {
    tissue_sim::cli::main()
}
