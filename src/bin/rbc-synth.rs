//! `rbc-synth`: TODO(owner).
fn main() {
    eprintln!("rbc-synth: not implemented yet");
    std::process::exit(2);
}
