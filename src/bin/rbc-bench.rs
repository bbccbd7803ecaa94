//! `rbc-bench`: TODO(owner).
fn main() {
    eprintln!("rbc-bench: not implemented yet");
    std::process::exit(2);
}
