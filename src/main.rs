fn main() {
    println!("wfem");
}
