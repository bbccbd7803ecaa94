//! `rbc-simulate`: TODO(owner).
fn main() {
    eprintln!("rbc-simulate: not implemented yet");
    std::process::exit(2);
}
