fn main() {
    println!("{}", lanterna::gpu::BINDING_COUNT);
}
