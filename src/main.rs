fn main() {
    println!("dpm");
}
