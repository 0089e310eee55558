//! Section 3 of the report: typing and membership (seed 002 §5): a hinge
//! joining two spiral parts of one object, and two objects that collide.

use std::fmt::Write as _;
use std::path::Path;

use op_experiments::membership::{run_collision, run_hinge};

use crate::{scene_file, Res};

/// The hinge spiral and the two colliding objects, scenes read from
/// `root`.
pub(crate) fn typing_and_membership(root: &Path) -> Res<String> {
    let mut s = String::from("## 3. Typing and membership (seed 002 §5)\n\n");
    let hinge = run_hinge(&scene_file(root, "hinge_spiral")?)?;
    let _ = writeln!(
        s,
        "**Hinge** (`scenes/hinge_spiral.ron`): one object of 13 particles, two spiral parts \
         (Standard(1): particles 0-5, Standard(2): 7-12) joined by particle 6, a Hinge, \
         unoriented (spacing only: a free joint). The parts interact completely with the hinge \
         and only repel each other. Pulled by the recipe's end forces and released:\n\n\
         | measure | value |\n|---|---|\n\
         | longest bond along the chain over the run | {:.3} r0 (maximum cohesion attraction at 1.294 r0: never broken) |\n\
         | longest bond to the hinge | {:.3} r0 |\n\
         | parts' own rest shape error, max during the pull | {:.3}, {:.3} |\n\
         | parts' own rest shape error, final | {:.5}, {:.5} |\n\
         | whole object's rest shape error, max / final | {:.3} / {:.3} |\n\
         | angle at the hinge, rest / final | {:.1}° / {:.1}° |\n\
         | distance between the parts' centroids, rest / final | {:.2} / {:.2} r0 |\n\n\
         It moves as one object: the bonds to the hinge hold through the pull and the release. \
         Each part returns to its own shape; the hinge, unoriented, has no bending memory and \
         keeps the angle the load left. Typing keeps the two parts from interacting with each \
         other (they only repel), so all that joins them is the hinge.\n",
        hinge.max_bond,
        hinge.max_hinge_bond,
        hinge.part_errors_max[0],
        hinge.part_errors_max[1],
        hinge.part_errors_final[0],
        hinge.part_errors_final[1],
        hinge.object_error_max,
        hinge.object_error_final,
        hinge.hinge_angle.0,
        hinge.hinge_angle.1,
        hinge.part_distance.0,
        hinge.part_distance.1
    );
    let c = run_collision(&scene_file(root, "colliding_objects")?, 0.05)?;
    let _ = writeln!(
        s,
        "**Two objects** (`scenes/colliding_objects.ron`): two seed spirals (recipe material), \
         pushed towards each other after settling. Particles of different objects only repel, \
         so they bounce and never merge:\n\n\
         | measure | value |\n|---|---|\n\
         | closest approach (particles of different objects) | {:.3} r0 at t = {:.2} |\n\
         | net force of one object on the other along their centroids: most repulsive | {:.3} |\n\
         | same, most attractive | {:.1e} (round-off: never attractive, no complete interaction) |\n\
         | centroid separation at closest approach / at the end | {:.2} / {:.2} r0 |\n\
         | distance between the objects at the end | {:.2} r0 (beyond every cut-off) |\n\
         | rest shape errors, max | {:.3}, {:.3} |\n\
         | rest shape errors, final | {:.4}, {:.4} |\n\
         | samples | {} (every 0.05 time units) |\n",
        c.min_distance,
        c.closest_at,
        c.max_repulsion,
        c.max_attraction,
        c.separation.0,
        c.separation.1,
        c.final_distance,
        c.max_errors[0],
        c.max_errors[1],
        c.final_errors[0],
        c.final_errors[1],
        c.samples
    );
    Ok(s)
}
