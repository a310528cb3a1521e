//! `aurora`: the command line. A thin layer over the library: [`cli::args`]
//! parses the arguments, [`cli::run`] composes the library's stages for the
//! command (bake -> files, files -> render), and [`cli::exit`] maps the
//! result to the exit status in one place: 0 on success, 2 for bad input
//! (scene file, arguments, an unreadable VDB or one the renderer refuses, a
//! scene the bake cannot honour), 1 for anything else.

mod cli;

fn main() {
    cli::out::reopen_closed_descriptors();
    cli::out::ignore_file_size_signal();
    cli::out::on_interrupt_remove_locks();
    aurora::util::memory::tune_allocator();
    let args = cli::args::parse();
    let json = args.json_errors();
    let code = cli::exit::code(cli::run(args), json);
    std::process::exit(code);
}
