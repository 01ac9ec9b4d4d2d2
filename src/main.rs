//! The `lobelight` command; everything it does is in `lobelight::cli`.

fn main() -> std::process::ExitCode {
    lobelight::cli::main()
}
