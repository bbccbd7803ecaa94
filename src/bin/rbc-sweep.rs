//! `rbc-sweep`: TODO(owner).
fn main() {
    eprintln!("rbc-sweep: not implemented yet");
    std::process::exit(2);
}
