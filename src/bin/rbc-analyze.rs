//! `rbc-analyze`: TODO(owner).
fn main() {
    eprintln!("rbc-analyze: not implemented yet");
    std::process::exit(2);
}
