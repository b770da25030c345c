//! Prints a built-in mechanism's `[[body]]`, `[[joint]]` and `[[finger]]`
//! tables in scene-file syntax; the built-in scenes in `scenes/` were made this
//! way (a header with `[scene]`, `[solver]` and `[[device]]` written by hand).
//!
//! `cargo run -p haptloop-solver --example scene_tables -- four-bar right`

use haptloop_solver::mechanisms;
use haptloop_solver::scene::mechanism_tables;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (name, device) = match args.as_slice() {
        [n, d] => (n.as_str(), d.clone()),
        _ => {
            eprintln!(
                "usage: scene_tables <four-bar|stewart|sphere-toy|sphere-toy-33|sphere-toy-400|cluttered|bennett|lattice|lattice-RxC|chain|chain-N> <device-name>"
            );
            std::process::exit(2);
        }
    };
    let builder = match name {
        "four-bar" => mechanisms::four_bar_builder(),
        "stewart" => mechanisms::stewart_builder(),
        "sphere-toy" => mechanisms::sphere_toy_builder(),
        "cluttered" => mechanisms::cluttered_builder(100),
        "bennett" => mechanisms::bennett_builder(),
        "lattice" => mechanisms::lattice_builder(),
        "chain" => mechanisms::chain_builder(),
        sized if sized.starts_with("lattice-") => {
            let shape = sized["lattice-".len()..]
                .split_once('x')
                .and_then(|(r, c)| Some((r.parse().ok()?, c.parse().ok()?)));
            let Some((rows, cols)) = shape else {
                eprintln!("sized lattices: lattice-RxC, e.g. lattice-2x8");
                std::process::exit(2);
            };
            mechanisms::lattice_sized(rows, cols)
        }
        sized if sized.starts_with("chain-") => {
            let Ok(links) = sized["chain-".len()..].parse() else {
                eprintln!("sized chains: chain-N, e.g. chain-16");
                std::process::exit(2);
            };
            mechanisms::chain_sized(links)
        }
        sized if sized.starts_with("sphere-toy-") => {
            let shape = sized["sphere-toy-".len()..]
                .parse()
                .ok()
                .and_then(mechanisms::sphere_toy_shape);
            let Some((rings, per_ring)) = shape else {
                eprintln!("sized sphere toys: sphere-toy-33, sphere-toy-132, sphere-toy-400");
                std::process::exit(2);
            };
            mechanisms::sphere_toy_sized(rings, per_ring)
        }
        other => {
            eprintln!(
                "unknown mechanism `{other}`; expected four-bar, stewart, sphere-toy, sphere-toy-N, cluttered, bennett, lattice, lattice-RxC, chain or chain-N"
            );
            std::process::exit(2);
        }
    };
    print!("{}", mechanism_tables(&builder, &|_| device.clone()));
}
