//! Generates the low-poly models voxel-art ships in `assets/models/` (made by this project, not copied):
//! `cargo run -p voxel-core --example make_models`.

use std::f32::consts::{FRAC_PI_2, PI};
use std::path::Path;

use voxel_core::TriangleSoup;
use voxel_core::glb::soup_to_glb;
use voxel_core::shapes::{IndexedMesh, cuboid, cylinder, dome, torus, uv_sphere};

/// Linear RGB from sRGB hex, opaque.
fn rgb(hex: u32) -> [f32; 4] {
    let c = |shift: u32| voxel_core::srgb::srgb_to_linear(((hex >> shift) & 0xff) as u8);
    [c(16), c(8), c(0), 1.0]
}

/// A thin leaf: a flattened sphere tilted about z.
fn leaf(length: f32, width: f32, tilt: f32) -> IndexedMesh {
    uv_sphere(1.0, 8).scaled([length, 0.04, width]).rotated([0.0, 0.0, 1.0], tilt)
}

fn cherry() -> TriangleSoup {
    let mut soup = TriangleSoup::default();
    let red = rgb(0xc8102e);
    soup.add_mesh(&uv_sphere(1.0, 12).translated([-1.0, 0.0, 0.0]), red, "left cherry");
    soup.add_mesh(&uv_sphere(0.95, 12).translated([1.0, 0.15, 0.2]), red, "right cherry");
    let stem = rgb(0x4a7a1e);
    soup.add_mesh(
        &cylinder(0.07, 0.0, 2.6, 8).rotated([0.0, 0.0, 1.0], -0.35).translated([-1.0, 0.8, 0.0]),
        stem,
        "left stem",
    );
    soup.add_mesh(
        &cylinder(0.07, 0.0, 2.5, 8).rotated([0.0, 0.0, 1.0], 0.45).translated([1.0, 0.9, 0.2]),
        stem,
        "right stem",
    );
    soup.add_mesh(&leaf(1.0, 0.45, 0.3).translated([0.9, 3.3, 0.1]), rgb(0x6abf3a), "leaf");
    soup
}

fn apple() -> TriangleSoup {
    let mut soup = TriangleSoup::default();
    soup.add_mesh(&uv_sphere(1.5, 14).scaled([1.0, 0.88, 1.0]), rgb(0xe8423f), "apple");
    soup.add_mesh(&cylinder(0.09, 1.0, 2.0, 8).rotated([0.0, 0.0, 1.0], 0.15), rgb(0x6b4226), "stem");
    soup.add_mesh(&leaf(0.8, 0.35, -0.4).translated([0.7, 1.75, 0.0]), rgb(0x5fae3b), "leaf");
    soup
}

fn avocado_half() -> TriangleSoup {
    // Lying cut face up: skin below, flesh disc on the cut, the pit half standing out of it.
    let mut soup = TriangleSoup::default();
    let shape = [1.0, 0.55, 1.45];
    soup.add_mesh(&dome(1.0, 10, true).rotated([1.0, 0.0, 0.0], PI).scaled(shape), rgb(0x2f4f1c), "skin");
    soup.add_mesh(&cylinder(0.92, 0.0, 0.08, 40).scaled([1.0, 1.0, 1.45]), rgb(0xd7e27a), "flesh");
    soup.add_mesh(&dome(0.45, 8, true).translated([0.0, 0.08, -0.15]), rgb(0x7a4a2a), "pit");
    soup
}

fn fried_egg() -> TriangleSoup {
    // The white is a thin disc (a tenth of a cell at the default grid is enough to vanish between samples).
    let mut soup = TriangleSoup::default();
    let white = cylinder(1.0, 0.0, 0.06, 28).scaled([2.2, 1.0, 1.8]).translated([0.2, 0.0, 0.0]);
    soup.add_mesh(&white, rgb(0xf8f4e8), "white");
    soup.add_mesh(&dome(0.75, 8, true).scaled([1.0, 0.7, 1.0]).translated([-0.2, 0.06, 0.1]), rgb(0xffb21c), "yolk");
    soup
}

fn donut() -> TriangleSoup {
    // Dough below, pink icing on top as vertex colours, and sprinkles.
    let mut soup = TriangleSoup::default();
    let body = torus(1.4, 0.65, 28);
    soup.add_mesh(&body, [1.0; 4], "donut");
    let (dough, icing) = (rgb(0xd9a066), rgb(0xf48fb1));
    // The donut is the soup's only part so far.
    let colors: Vec<[f32; 4]> = soup.positions().iter().map(|p| if p[1] > 0.12 { icing } else { dough }).collect();
    soup.colors_mut().copy_from_slice(&colors);
    let sprinkle_colors = [0xffffff, 0x4fc3f7, 0xffee58, 0x81c784, 0xba68c8];
    for k in 0..14 {
        let a = k as f32 * 0.45 + 0.2;
        let r = 1.4 + 0.35 * ((k * 7 % 5) as f32 / 4.0 - 0.5);
        let sprinkle = cuboid([-0.16, -0.04, -0.04], [0.16, 0.04, 0.04])
            .rotated([0.0, 1.0, 0.0], a * 3.0)
            .translated([r * a.cos(), 0.62, r * a.sin()]);
        soup.add_mesh(&sprinkle, rgb(sprinkle_colors[k % sprinkle_colors.len()]), "sprinkle");
    }
    soup
}

fn mushroom() -> TriangleSoup {
    // The cap is an open shell (no underside): parity cannot close it, the surface shell keeps it.
    let mut soup = TriangleSoup::default();
    soup.add_mesh(&cylinder(0.42, 0.0, 1.5, 16).scaled([1.0, 1.0, 0.9]), rgb(0xf1e3c8), "stem");
    soup.add_mesh(&dome(1.5, 10, false).scaled([1.0, 0.75, 1.0]).translated([0.0, 1.35, 0.0]), rgb(0xd32f2f), "cap");
    for (k, (a, h)) in
        [(0.3f32, 0.55f32), (1.6, 0.45), (2.9, 0.6), (4.2, 0.5), (5.3, 0.4), (0.0, 1.0)].iter().enumerate()
    {
        let (r, y) = if k == 5 { (0.0, 1.12) } else { (1.5 * h.cos() * 0.95, 1.12 * h.sin() + 0.1) };
        let spot = uv_sphere(0.22, 6).scaled([1.0, 0.35, 1.0]);
        let tilt = if k == 5 { 0.0 } else { FRAC_PI_2 - h };
        let spot = spot.rotated([-a.sin(), 0.0, a.cos()], tilt).translated([r * a.cos(), 1.35 + y, r * a.sin()]);
        soup.add_mesh(&spot, rgb(0xfafafa), "spot");
    }
    soup
}

/// Builds one model.
type Maker = fn() -> TriangleSoup;

fn main() {
    let out = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/models");
    std::fs::create_dir_all(&out).expect("create assets/models");
    let models: [(&str, Maker); 6] = [
        ("cherry", cherry),
        ("apple", apple),
        ("avocado-half", avocado_half),
        ("fried-egg", fried_egg),
        ("donut", donut),
        ("mushroom", mushroom),
    ];
    for (name, make) in models {
        let path = out.join(format!("{name}.glb"));
        let soup = make();
        std::fs::write(&path, soup_to_glb(&soup).expect("encode model")).expect("write model");
        println!("{} ({} triangles, {} parts)", path.display(), soup.triangle_count(), soup.parts.len());
    }
}
