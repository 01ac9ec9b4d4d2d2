//! The `lobelight` command; everything it does is in `lobelight::cli`.

/// A scan's large arrays on huge pages (`lobelight::large_pages`).
#[global_allocator]
static ALLOCATOR: lobelight::large_pages::LargePages = lobelight::large_pages::LargePages;

fn main() -> std::process::ExitCode {
    lobelight::cli::main()
}
