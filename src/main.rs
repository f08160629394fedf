fn main() {
    println!("cliffmap");
}
