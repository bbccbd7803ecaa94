//! `rbc-predict`: TODO(owner).
fn main() {
    eprintln!("rbc-predict: not implemented yet");
    std::process::exit(2);
}
