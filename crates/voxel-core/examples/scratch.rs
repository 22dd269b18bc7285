use voxel_core::*;
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let s = load_file(args[1].as_ref()).unwrap();
    let res: u32 = args[2].parse().unwrap();
    let n: usize = args.get(3).map_or(3, |a| a.parse().unwrap());
    for _ in 0..n {
        let o = VoxelizeOptions { grid: GridSize::Resolution(res), ..Default::default() };
        let t = std::time::Instant::now();
        let m = voxelize(&s, &o).unwrap();
        println!("{:?} {:?}", t.elapsed(), m.stats);
    }
}
