//! Triangulation of an oriented particle surface for rendering (seed 000
//! §5).
//!
//! **Rule** (seed 000 §5): a triangle of *mutual neighbours* (every pair
//! of its three particles within [`TriangulationParams::radius`]) is kept
//! when the smallest sphere through its three particles holds no other
//! particle: the 2-D Delaunay empty-circle test carried to 3-D.
//!
//! **The sphere.** Every sphere through three points has its centre on the
//! line through the triangle's circumcentre perpendicular to its plane; the
//! smallest is centred at the circumcentre, with the circumradius. This is
//! the sphere the paper names ("the smallest sphere circumscribing each
//! triangle") and it is used for every triangle, acute or obtuse. For an
//! obtuse triangle the circumcentre lies outside the triangle and the
//! sphere is larger than the smallest sphere *enclosing* the triangle (the
//! one on its longest edge): we keep the circumscribing sphere because it
//! is what makes the test the Delaunay one (a flat patch gets its Delaunay
//! triangulation, and of two triangles sharing an edge across a convex
//! quadrilateral exactly one survives), whereas the enclosing sphere would
//! keep both diagonals of a flat quadrilateral with one obtuse triangle.
//!
//! **Tilt** (our addition, using the particles' orientation): a triangle
//! whose plane is tilted by more than [`TriangulationParams::max_tilt`]
//! from the mean of its three particle normals is dropped. Three nearly
//! collinear mutual neighbours (a sliver along a curved surface, e.g. on a
//! sphere or a torus) have a circumsphere centred far away in an almost
//! arbitrary plane; when that plane stands across the surface the sphere
//! can miss every other particle, and the sliver would be kept across
//! genuine triangles (edges with three triangles). Such a sliver's plane
//! is far from tangent, whereas the plane of a genuine triangle of a
//! surface sampled finely with respect to its curvature (the paper's
//! condition) is close to its particles' tangent planes.
//!
//! The particles' normals are their own state, though, and they need not
//! lie along the surface their positions sample: under a finger denting a
//! shape-memory shell (seed 002 §4) the form term keeps the normals'
//! sphere pattern while the positions take the dent, and the dent's walls
//! stood 60-70° from their particles' normals, so the walls' triangles
//! failed the test and the surface showed holes while no particle left the
//! layer. A triangle tilted beyond the limit from its particle normals is
//! therefore kept when it is within the limit of its corners' *fitted*
//! normals (each the normal of the plane fitted to the particle and its
//! neighbours within the radius, turned to the particle's side): the
//! surface the positions sample. A sliver standing across the surface is
//! across both. On `scenes/fig_12_plastic_memory.ron` the particle normals
//! alone close the exported shell in 41 of 101 frames, the fitted ones too
//! in 61.
//!
//! **Inside** means `|x - c|^2 < R^2 (1 - 1e-9)`. A particle *on* the
//! sphere (within a relative `1e-9` of `R^2`: co-circular particles, as in a
//! square grid or between the symmetric rings of a generated torus) is a
//! tie, broken by rank (particle id) so that exactly one triangulation of
//! the co-circular set survives, the fan from its smallest id: the tie
//! counts as inside when its rank is below the triangle's smallest, or when
//! it lies (in the triangle's plane) across the edge opposite the
//! triangle's smallest-rank corner. Keeping all ties outside would keep
//! both diagonals of a co-circular quadrilateral (edges in three
//! triangles); keeping them all inside would leave a hole. Degenerate
//! triangles (collinear, non-finite circumradius) are never kept.
//!
//! **Crossed diagonals** (our addition): on a curved surface four
//! particles `p, q, r, s` around a quadrilateral can pass the sphere test
//! with both diagonals, because each triangle's sphere is centred in its
//! own plane and the fourth particle lies off that plane, outside it (the
//! two triangles of each diagonal make edges in three triangles). Of two
//! such pairs the one kept is the pair whose diagonal is the Delaunay one
//! in the plane normal to the mean of the four particle normals (the
//! empty-circle test the rule carries to 3-D, taken back to the tangent
//! plane); an exact tie keeps the diagonal through the smallest rank, like
//! the co-circular ties above. Applied in edge order until no crossed pair
//! is left.
//!
//! **Overfull edges** (our addition): an edge still held by more than two
//! triangles after that (one corner inside the triangle of the other three
//! in the tangent plane, or a fold of a crowded patch) keeps at most one
//! triangle on each side of it in the plane normal to its two particle
//! normals: the one whose opposite corner sees the edge under the largest
//! angle, the Delaunay choice. On coarse jittered spheres this takes every
//! seed of the test to a closed sphere (5 of 8 before), and it removed the
//! last edges in three triangles from the torus of seed 000 fig. 14.
//!
//! **Links** (our addition): [`triangulate_linked`] keeps only triangles
//! with at least two of their three edges joining particles that still
//! interact (the caller's predicate: e.g. closer than the spacing cut-off
//! and, in a bonded material, bonded). The surface of seed 000 §5 shows
//! what holds together, so a cut (seed 000 §6, fig. 7) or a tear (§8, fig.
//! 12c) opens in the triangulation as soon as the pairs across it stop
//! interacting, even while they are still mutual neighbours within the
//! radius: a triangle across a cut has one corner on one side and two on
//! the other, so two of its edges cross the cut. One unlinked edge is
//! kept: the long diagonal of a cell whose four sides hold together (the
//! two corners are held through the other two) is not a cut.
//!
//! **Held cells** (our addition): a hole of four edges whose four sides
//! all hold together (linked) is a cell of the surface that no triangle
//! covers, not a cut: under a finger denting a shell, a folded cell whose
//! diagonals (1.501 and 1.504 r0) lost the sphere and tilt tests on both
//! sides. It is closed by the two triangles on its shorter diagonal, the
//! one unlinked edge a triangle may have. A hole of three held sides is a
//! missing triangle and gets it. Longer holes stay open.
//!
//! **Sides** (our addition, for point-set fitting,
//! [`TriangulationParams::separate_sides`]): the two sides of a feature
//! thinner than the radius (an ear, a finger of a scan) are two sheets
//! whose particles face away from each other. With the option, particles
//! whose normals are more than 90° apart are never mutual neighbours (no
//! triangle bridges the two sides: the stretching rule's one-sheet test,
//! seed 000 §7, carried to the triangulation), and a particle facing more
//! than 90° away from a triangle's normal (the sum of its corners') does
//! not count in its sphere test (the other side does not empty this
//! side's triangles). On the 26,002 vertices of a scanned armadillo,
//! whose ears are 0.6-0.8 spacings thick, the triangles across its ears
//! made handles and Möbius bands (χ -5).
//!
//! **Orientation**: each triangle is wound so that its geometric normal
//! `(p_b - p_a) x (p_c - p_a)` points along the sum of its three particle
//! normals `n = R(q) a` (on a closed surface with outward normals the faces
//! face outward).
//!
//! **Output** is deterministic at any thread count: triangles as particle
//! *ids*, each rotated so its smallest id comes first, sorted.
//!
//! Helpers: [`Triangulation::euler_characteristic`] (`V - E + F`),
//! [`Triangulation::boundary_loops`], [`Triangulation::is_manifold`],
//! [`Triangulation::is_consistently_oriented`].

use std::collections::BTreeSet;

use kiddo::{ImmutableKdTree, SquaredEuclidean};
use rayon::prelude::*;

use op_dynamics::error::{self, ParamError};
use op_dynamics::math::{Point3, Real, Vec3};
use op_dynamics::neighbours::{search, NeighbourBackend, PairList};
use op_dynamics::particles::Particles;

/// Settings of [`triangulate`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriangulationParams {
    /// Mutual-neighbour distance (absolute length), finite and > 0: a
    /// triangle's three edges must be at most this long. Around 1.5-1.8
    /// times the rest spacing `r0` (long enough for the edges of a
    /// stretched sheet, short enough to skip second neighbours).
    pub radius: Real,
    /// Largest angle (radians) between a triangle's plane normal and the
    /// mean of its particle normals (or, failing that, of its corners'
    /// fitted normals: "Tilt" in the module docs), in (0, pi/2]. Default:
    /// pi/3 (60°).
    pub max_tilt: Real,
    /// Keep the two sides of a thin feature apart (see "Sides" in the
    /// module docs): particles whose normals are more than 90° apart are
    /// never mutual neighbours, and a particle whose normal is more than
    /// 90° from a triangle's does not count in its sphere test. Default:
    /// false (the scenes' surfaces; point-set fitting sets it).
    pub separate_sides: bool,
}

impl TriangulationParams {
    /// Parameters with `radius = factor * r0` and the default tilt.
    pub fn from_spacing(r0: Real, factor: Real) -> Self {
        Self::with_radius(r0 * factor)
    }

    /// Parameters with this mutual-neighbour radius and the default tilt.
    pub fn with_radius(radius: Real) -> Self {
        TriangulationParams {
            radius,
            max_tilt: std::f64::consts::FRAC_PI_3,
            separate_sides: false,
        }
    }

    /// Checks that the radius is finite and > 0 and the tilt in (0, pi/2].
    pub fn validate(&self) -> Result<(), ParamError> {
        error::positive("radius", self.radius)?;
        error::check(
            "max_tilt",
            self.max_tilt,
            self.max_tilt > 0.0 && self.max_tilt <= std::f64::consts::FRAC_PI_2,
            "must be in (0, pi/2] radians",
        )
    }
}

/// Relative width of the tie band of the emptiness test: a particle is
/// inside the sphere when `|x - c|^2 < R^2 (1 - TIE)`, on it (a tie, broken
/// by rank) up to `R^2 (1 + TIE)`.
const TIE: Real = 1e-9;

/// A triangulation of particles, triangles as particle ids.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Triangulation {
    /// Triangles `[a, b, c]` (particle ids), wound along the particle
    /// normals, smallest id first, sorted.
    pub triangles: Vec<[u32; 3]>,
}

/// Triangulates the particles of `particles` (seed 000 §5; see the module
/// documentation for the rule). Particles with a non-finite position take no
/// part.
pub fn triangulate(
    particles: &Particles,
    params: &TriangulationParams,
) -> Result<Triangulation, ParamError> {
    let normals: Vec<Vec3> = (0..particles.len()).map(|s| particles.normal(s)).collect();
    let slots = triangulate_ranked(
        particles.positions(),
        &normals,
        particles.ids(),
        params,
        &|_, _| true,
    )?;
    let ids = particles.ids();
    let mut triangles: Vec<[u32; 3]> = slots
        .into_iter()
        .map(|t| canonical([ids[t[0] as usize], ids[t[1] as usize], ids[t[2] as usize]]))
        .collect();
    triangles.sort_unstable();
    Ok(Triangulation { triangles })
}

/// The same rule on bare points with normals: triangles as indices into
/// `positions`, wound along `normals`, smallest index first, sorted. Ties
/// (co-circular points) are broken by index.
///
/// # Errors
/// When the radius is not finite and positive, or `normals` does not have
/// one entry per position.
pub fn triangulate_points(
    positions: &[Point3],
    normals: &[Vec3],
    params: &TriangulationParams,
) -> Result<Vec<[u32; 3]>, ParamError> {
    triangulate_linked(positions, normals, params, &|_, _| true)
}

/// [`triangulate_points`] keeping only triangles with at least two of
/// their three edges *linked*: `linked(a, b)` (indices into `positions`,
/// `a < b`) says whether the two points still interact (see "Links" in the
/// module docs). Every point, linked or not, still counts in the
/// empty-sphere test.
///
/// # Errors
/// As [`triangulate_points`].
pub fn triangulate_linked(
    positions: &[Point3],
    normals: &[Vec3],
    params: &TriangulationParams,
    linked: &Linked<'_>,
) -> Result<Vec<[u32; 3]>, ParamError> {
    let ranks: Vec<u32> = (0..positions.len() as u32).collect();
    triangulate_ranked(positions, normals, &ranks, params, linked)
}

/// Whether two points (indices, smaller first) still interact.
pub type Linked<'a> = dyn Fn(u32, u32) -> bool + Sync + 'a;

/// [`triangulate_linked`] with ties broken by `ranks` (one per position,
/// distinct).
fn triangulate_ranked(
    positions: &[Point3],
    normals: &[Vec3],
    ranks: &[u32],
    params: &TriangulationParams,
    linked: &Linked<'_>,
) -> Result<Vec<[u32; 3]>, ParamError> {
    let mut out = sphere_rule(positions, normals, ranks, params, linked)?;
    let crowded = resolve_crossed_diagonals(&mut out, positions, normals, ranks);
    resolve_overfull_edges(&mut out, crowded, positions, normals, ranks);
    held_cells::close_held_cells(&mut out, positions, linked);
    Ok(out)
}

/// The triangles the sphere test and the tilt limit keep, before crossed
/// diagonals are resolved: canonical, sorted.
fn sphere_rule(
    positions: &[Point3],
    normals: &[Vec3],
    ranks: &[u32],
    params: &TriangulationParams,
    linked: &Linked<'_>,
) -> Result<Vec<[u32; 3]>, ParamError> {
    params.validate()?;
    if normals.len() != positions.len() {
        return Err(ParamError::Invalid {
            field: "normals".into(),
            message: format!(
                "{} normals for {} positions (one per position needed)",
                normals.len(),
                positions.len()
            ),
        });
    }
    let n = positions.len();
    let mut half = PairList::new();
    search(
        NeighbourBackend::CellList,
        positions,
        params.radius,
        &mut half,
    );
    let full = half.full_rows();
    let finite: Vec<[Real; 3]> = positions
        .iter()
        .filter(|p| p.iter().all(|c| c.is_finite()))
        .map(|p| [p.x, p.y, p.z])
        .collect();
    let index: Vec<u32> = (0..n as u32)
        .filter(|&i| positions[i as usize].iter().all(|c| c.is_finite()))
        .collect();
    let tree = (finite.len() >= 2)
        .then(|| ImmutableKdTree::<Real, 3>::new_from_slice(&finite).ok())
        .flatten();
    let fitted = fitted_normals(positions, normals, &full);
    let ctx = Ctx {
        positions,
        normals,
        fitted: &fitted,
        half: &half,
        full: &full,
        radius: params.radius,
        cos_tilt: params.max_tilt.cos(),
        separate_sides: params.separate_sides,
        tree: tree.as_ref(),
        index: &index,
        ranks,
        linked,
    };
    let per: Vec<Vec<[u32; 3]>> = (0..n)
        .into_par_iter()
        .map(|i| ctx.triangles_of(i))
        .collect();
    // In parallel: the order they are gathered in does not matter, and
    // equal triangles are the same bits, so the sorted list is the same.
    let mut out: Vec<[u32; 3]> = per
        .into_par_iter()
        .flat_map_iter(|ts| ts.into_iter().map(canonical))
        .collect();
    out.par_sort_unstable();
    Ok(out)
}

/// The vertices of `t`, ascending (the key of a triangle whatever its
/// winding).
fn sorted(t: [u32; 3]) -> [u32; 3] {
    let mut k = t;
    k.sort_unstable();
    k
}

/// Removes, of every two triangle pairs spanning the same four particles
/// with crossing diagonals, the pair whose diagonal is not Delaunay in the
/// tangent plane (see the module docs). `tris` (sorted, no two of the same
/// vertices: the sphere rule's) stays sorted. Returns the edges left held
/// by more than two triangles, with their corners.
fn resolve_crossed_diagonals(
    tris: &mut Vec<[u32; 3]>,
    positions: &[Point3],
    normals: &[Vec3],
    ranks: &[u32],
) -> Vec<Crowded> {
    // The vertex sets, ascending.
    let mut keys: Vec<[u32; 3]> = tris.par_iter().map(|&t| sorted(t)).collect();
    keys.par_sort_unstable();
    debug_assert!(
        keys.windows(2).all(|w| w[0] < w[1]),
        "the sphere rule keeps a triangle once"
    );
    // One edge table for all rounds: the edges crowded after a round are
    // among those crowded before it (`still_crowded`), and on a million
    // particles the table is most of this pass (0.43 s of 0.6 s a round).
    let mut crowded = crowded_edges(&keys);
    loop {
        let has = |a: u32, b: u32, c: u32| keys.binary_search(&sorted([a, b, c])).is_ok();
        let mut drop: BTreeSet<[u32; 3]> = BTreeSet::new();
        for ((p, q), others) in &crowded {
            let (p, q) = (*p, *q);
            for (x, &r) in others.iter().enumerate() {
                for &s in &others[x + 1..] {
                    // All four faces of the tetrahedron p, q, r, s kept.
                    if !(has(r, s, p) && has(r, s, q)) {
                        continue;
                    }
                    let Some([a, b, c, d]) = crossing_diagonals([p, q, r, s], positions, normals)
                    else {
                        continue;
                    };
                    let pair =
                        |a: u32, b: u32, c: u32, d: u32| [sorted([a, b, c]), sorted([a, b, d])];
                    let (ab, cd) = (pair(a, b, c, d), pair(c, d, a, b));
                    if ab.iter().chain(&cd).any(|t| drop.contains(t)) {
                        continue;
                    }
                    let keep_ab = delaunay_diagonal([a, b, c, d], positions, normals, ranks);
                    drop.extend(if keep_ab { cd } else { ab });
                }
            }
        }
        if drop.is_empty() {
            return crowded;
        }
        tris.retain(|&t| !drop.contains(&sorted(t)));
        keys.retain(|k| !drop.contains(k));
        crowded = still_crowded(crowded, &drop);
    }
}

/// An edge `(p, q)` (`p < q`) held by more than two triangles, with the
/// corner opposite it in each.
type Crowded = ((u32, u32), Vec<u32>);

/// The edges `(p, q)` (`p < q`) held by more than two of `tris`, ascending,
/// each with the corner opposite it in each triangle holding it (in the
/// order of `tris`).
fn crowded_edges(tris: &[[u32; 3]]) -> Vec<Crowded> {
    let table = EdgeTable::new(tris);
    (0..table.len())
        .filter(|&e| table.count(e) > 2)
        .map(|e| {
            let corners = table
                .slots(e)
                .iter()
                .map(|&s| tris[s as usize / 3][(s as usize % 3 + 2) % 3])
                .collect();
            (table.vertices(e), corners)
        })
        .collect()
}

/// [`crowded_edges`] of the triangles left when those of `dropped` (vertex
/// sets) go, from `crowded`, theirs before: a triangle going only lowers
/// the counts of its edges, so the edges crowded after are among those
/// before, with the corners that stayed (in the same order).
fn still_crowded(crowded: Vec<Crowded>, dropped: &BTreeSet<[u32; 3]>) -> Vec<Crowded> {
    crowded
        .into_iter()
        .filter_map(|((p, q), corners)| {
            let left: Vec<u32> = corners
                .into_iter()
                .filter(|&r| !dropped.contains(&sorted([p, q, r])))
                .collect();
            (left.len() > 2).then_some(((p, q), left))
        })
        .collect()
}

/// Keeps, of the triangles on an edge held by more than two, at most one on
/// each side of the edge in the tangent plane: the one whose opposite
/// corner sees the edge under the largest angle (the Delaunay one; an
/// exact tie keeps the smallest rank). Applied in edge order until no edge
/// is held by more than two. `tris` stays sorted; `crowded` are its
/// crowded edges ([`crowded_edges`]; the order of the corners does not
/// matter, ranks being distinct).
fn resolve_overfull_edges(
    tris: &mut Vec<[u32; 3]>,
    mut crowded: Vec<Crowded>,
    positions: &[Point3],
    normals: &[Vec3],
    ranks: &[u32],
) {
    loop {
        let mut drop: BTreeSet<[u32; 3]> = BTreeSet::new();
        for ((p, q), others) in &crowded {
            let (p, q) = (*p, *q);
            let (xp, xq) = (positions[p as usize], positions[q as usize]);
            let n = normals[p as usize] + normals[q as usize];
            let across = n.cross(&(xq - xp));
            // (side, -cos of the angle at the corner, rank): the best first.
            let mut ranked: Vec<(bool, Real, u32, u32)> = others
                .iter()
                .map(|&r| {
                    let xr = positions[r as usize];
                    let (u, v) = ((xp - xr).normalize(), (xq - xr).normalize());
                    (
                        across.dot(&(xr - xp)) > 0.0,
                        u.dot(&v),
                        ranks[r as usize],
                        r,
                    )
                })
                .collect();
            ranked.sort_by(|a, b| {
                (a.0, a.1, a.2)
                    .partial_cmp(&(b.0, b.1, b.2))
                    .unwrap_or(std::cmp::Ordering::Equal)
            });
            for (k, &(side, _, _, r)) in ranked.iter().enumerate() {
                if k > 0 && ranked[k - 1].0 == side {
                    drop.insert(sorted([p, q, r]));
                }
            }
        }
        if drop.is_empty() {
            return;
        }
        tris.retain(|&t| !drop.contains(&sorted(t)));
        crowded = still_crowded(crowded, &drop);
    }
}

/// A frame `(origin, u, w)` of the plane normal to the mean of the normals
/// of `v`, and the coordinates of a particle in it.
fn tangent_coordinates<'a>(
    v: &[u32],
    positions: &'a [Point3],
    normals: &[Vec3],
) -> impl Fn(u32) -> (Real, Real) + use<'a> {
    let n: Vec3 = v.iter().map(|&k| normals[k as usize]).sum();
    let n = if n.norm() > 0.0 {
        n.normalize()
    } else {
        Vec3::z()
    };
    let u = op_dynamics::math::tangent_axis(&n).normalize();
    let w = n.cross(&u);
    let origin = positions[v[0] as usize];
    move |k: u32| {
        let d = positions[k as usize] - origin;
        (d.dot(&u), d.dot(&w))
    }
}

/// The four corners reordered `[a, b, c, d]` so that `(a, b)` and `(c, d)`
/// are the diagonals of the quadrilateral they make in the tangent plane
/// (the two segments that cross), or None when no pairing crosses (one
/// corner inside the triangle of the others).
fn crossing_diagonals(v: [u32; 4], positions: &[Point3], normals: &[Vec3]) -> Option<[u32; 4]> {
    let flat = tangent_coordinates(&v, positions, normals);
    let side = |o: (Real, Real), a: (Real, Real), b: (Real, Real)| {
        (a.0 - o.0) * (b.1 - o.1) - (a.1 - o.1) * (b.0 - o.0)
    };
    let cross = |a: u32, b: u32, c: u32, d: u32| {
        let (pa, pb, pc, pd) = (flat(a), flat(b), flat(c), flat(d));
        side(pa, pb, pc) * side(pa, pb, pd) < 0.0 && side(pc, pd, pa) * side(pc, pd, pb) < 0.0
    };
    let [p, q, r, s] = v;
    [[p, q, r, s], [p, r, q, s], [p, s, q, r]]
        .into_iter()
        .find(|&[a, b, c, d]| cross(a, b, c, d))
}

/// True when the diagonal `(v[0], v[1])` of the quadrilateral with the
/// other corners `v[2]`, `v[3]` is the Delaunay one in the plane normal to
/// the mean of the four normals: `v[3]` outside the circle through
/// `v[0], v[1], v[2]`. An exact tie keeps the diagonal through the
/// smallest rank.
fn delaunay_diagonal(v: [u32; 4], positions: &[Point3], normals: &[Vec3], ranks: &[u32]) -> bool {
    let flat = tangent_coordinates(&v, positions, normals);
    let [a, b, c, d] = v.map(flat);
    // In-circle determinant of d against (a, b, c), signed by the
    // orientation of (a, b, c).
    let orient = (b.0 - a.0) * (c.1 - a.1) - (b.1 - a.1) * (c.0 - a.0);
    let row = |p: (Real, Real)| {
        let (x, y) = (p.0 - d.0, p.1 - d.1);
        (x, y, x * x + y * y)
    };
    let (ra, rb, rc) = (row(a), row(b), row(c));
    let det = ra.0 * (rb.1 * rc.2 - rb.2 * rc.1) - ra.1 * (rb.0 * rc.2 - rb.2 * rc.0)
        + ra.2 * (rb.0 * rc.1 - rb.1 * rc.0);
    let inside = det * orient.signum();
    let scale = [ra.2, rb.2, rc.2].iter().fold(0.0, |m: Real, x| m.max(*x));
    if inside.abs() <= 1e-12 * scale * scale {
        let min_rank = |x: u32, y: u32| ranks[x as usize].min(ranks[y as usize]);
        return min_rank(v[0], v[1]) <= min_rank(v[2], v[3]);
    }
    // d inside the circle through a, b, c: the diagonal (c, d) is the
    // Delaunay one.
    inside < 0.0
}

struct Ctx<'a> {
    positions: &'a [Point3],
    normals: &'a [Vec3],
    /// Normals of the planes fitted to each particle's neighbours.
    fitted: &'a [Vec3],
    half: &'a PairList,
    full: &'a [Vec<u32>],
    radius: Real,
    cos_tilt: Real,
    separate_sides: bool,
    tree: Option<&'a ImmutableKdTree<Real, 3>>,
    index: &'a [u32],
    ranks: &'a [u32],
    linked: &'a Linked<'a>,
}

impl Ctx<'_> {
    /// Kept triangles `(i, j, k)` with `i < j < k`, wound along the normals.
    fn triangles_of(&self, i: usize) -> Vec<[u32; 3]> {
        let mut out = Vec::new();
        let row = self.half.row(i);
        let i32 = i as u32;
        let link = |a: u32, b: u32| (self.linked)(a.min(b), a.max(b)) as u8;
        let side = |a: u32, b: u32| {
            !self.separate_sides || self.normals[a as usize].dot(&self.normals[b as usize]) > 0.0
        };
        for (a, &j) in row.iter().enumerate() {
            if !side(i32, j) {
                continue;
            }
            let ij = link(i32, j);
            for &k in &row[a + 1..] {
                if !(side(i32, k) && side(j, k)) {
                    continue;
                }
                // Mutual: j and k neighbours too (rows ascending, k > j).
                if self.half.row(j as usize).binary_search(&k).is_err() {
                    continue;
                }
                // Two of the three edges linked: see "Links".
                if ij + link(i32, k) + link(j, k) < 2 {
                    continue;
                }
                let t = [i as u32, j, k];
                let Some(wound) = self.wound(t) else {
                    continue;
                };
                if let Some((c, r2)) = self.circumsphere(t) {
                    if self.is_empty(t, &c, r2) {
                        out.push(wound);
                    }
                }
            }
        }
        out
    }

    /// Centre and squared radius of the smallest sphere through the three
    /// points (centred at the circumcentre, in the triangle's plane); None
    /// for degenerate triangles.
    fn circumsphere(&self, t: [u32; 3]) -> Option<(Point3, Real)> {
        let a = self.positions[t[0] as usize];
        let u = self.positions[t[1] as usize] - a;
        let v = self.positions[t[2] as usize] - a;
        let w = u.cross(&v);
        let w2 = w.norm_squared();
        if w2 <= 1e-24 * u.norm_squared() * v.norm_squared() || !w2.is_finite() {
            return None;
        }
        // Circumcentre offset from a: (|u|^2 v - |v|^2 u) x w / (2 |w|^2).
        let off = (u.norm_squared() * v - v.norm_squared() * u).cross(&w) / (2.0 * w2);
        let r2 = off.norm_squared();
        r2.is_finite().then_some((a + off, r2))
    }

    /// No particle other than the triangle's inside the sphere (ties on
    /// the sphere broken by rank).
    fn is_empty(&self, t: [u32; 3], c: &Point3, r2: Real) -> bool {
        let (lo, hi) = (r2 * (1.0 - TIE), r2 * (1.0 + TIE));
        let ns: Vec3 = t.iter().map(|&m| self.normals[m as usize]).sum();
        let inside = |m: u32| {
            if t.contains(&m) || (self.separate_sides && self.normals[m as usize].dot(&ns) <= 0.0) {
                return false;
            }
            let d2 = (self.positions[m as usize] - c).norm_squared();
            d2 < lo || (d2 <= hi && self.tie_inside(t, m))
        };
        // A particle inside is within 2R of every vertex: when 2R fits in
        // the neighbour radius, the first vertex's neighbours are all the
        // candidates.
        if self.full[t[0] as usize].iter().any(|&m| inside(m)) {
            return false;
        }
        if 4.0 * r2 <= self.radius * self.radius {
            return true;
        }
        let Some(tree) = self.tree else {
            return true;
        };
        let mut empty = true;
        tree.query(&[c.x, c.y, c.z])
            .within::<SquaredEuclidean<Real>>(r2 * (1.0 + 1e-6))
            .unsorted()
            .visit(|res| {
                if inside(self.index[res.item as usize]) {
                    empty = false;
                }
            });
        empty
    }

    /// Whether `m`, on the sphere of `t`, counts as inside: its rank is
    /// below all of `t`'s, or it lies (in `t`'s plane) across the edge
    /// opposite `t`'s smallest-rank corner.
    fn tie_inside(&self, t: [u32; 3], m: u32) -> bool {
        let rank = |k: u32| self.ranks[k as usize];
        let k0 = (0..3).min_by_key(|&k| rank(t[k])).unwrap_or(0);
        if rank(m) < rank(t[k0]) {
            return true;
        }
        let p = |k: u32| self.positions[k as usize];
        let (a, b, c) = (p(t[k0]), p(t[(k0 + 1) % 3]), p(t[(k0 + 2) % 3]));
        let normal = (b - a).cross(&(c - a));
        let side = |x: Point3| (c - b).cross(&(x - b)).dot(&normal);
        side(a) * side(p(m)) < 0.0
    }

    /// `t` wound so its geometric normal points along the sum of the
    /// particle normals, or None when its plane is tilted by more than the
    /// largest tilt both from that sum and from the sum of its corners'
    /// fitted planes' normals (see "Tilt"; or when both sums cancel out).
    fn wound(&self, t: [u32; 3]) -> Option<[u32; 3]> {
        let p = |k: usize| self.positions[t[k] as usize];
        let face = (p(1) - p(0)).cross(&(p(2) - p(0)));
        let sum = |normals: &[Vec3]| -> Vec3 { t.iter().map(|&m| normals[m as usize]).sum() };
        let (ns, fitted) = (sum(self.normals), sum(self.fitted));
        let within = |n: &Vec3| {
            let scale = face.norm() * n.norm();
            scale > 0.0 && face.dot(n).abs() >= self.cos_tilt * scale
        };
        if !(within(&ns) || within(&fitted)) {
            return None;
        }
        // The fitted normals are turned to their particles' side, so either
        // sum gives the winding; the particles' own when it is defined.
        let along = if face.dot(&ns) != 0.0 { ns } else { fitted };
        Some(if face.dot(&along) < 0.0 {
            [t[0], t[2], t[1]]
        } else {
            t
        })
    }
}

/// For each particle, the normal of the plane fitted to it and its
/// neighbours within the radius (`full`): the direction of least spread of
/// those points about their mean, turned to the side of the particle's own
/// normal. Zero (no fitted plane, so no second chance in the tilt test)
/// for a particle with fewer than two neighbours, or whose neighbourhood
/// is not flat enough to have a plane: its least spread not below half its
/// middle one (points along a line, or a blob).
fn fitted_normals(positions: &[Point3], normals: &[Vec3], full: &[Vec<u32>]) -> Vec<Vec3> {
    (0..positions.len())
        .into_par_iter()
        .map(|i| {
            let row = &full[i];
            if row.len() < 2 {
                return Vec3::zeros();
            }
            let points = std::iter::once(i)
                .chain(row.iter().map(|&j| j as usize))
                .map(|k| &positions[k]);
            let (_, spread) = crate::fit::covariance(points);
            let eigen = spread.symmetric_eigen();
            let e = eigen.eigenvalues;
            let mut order = [0usize, 1, 2];
            order.sort_by(|&a, &b| e[a].total_cmp(&e[b]));
            let (least, middle) = (e[order[0]], e[order[1]]);
            // False for NaN spreads too.
            let flat = least < 0.5 * middle;
            if !flat {
                return Vec3::zeros();
            }
            let n: Vec3 = eigen.eigenvectors.column(order[0]).into_owned();
            if n.dot(&normals[i]) < 0.0 {
                -n
            } else {
                n
            }
        })
        .collect()
}

/// Rotates a triangle so its smallest entry comes first (winding kept).
fn canonical(t: [u32; 3]) -> [u32; 3] {
    let m = (0..3).min_by_key(|&k| t[k]).unwrap_or(0);
    [t[m], t[(m + 1) % 3], t[(m + 2) % 3]]
}

mod edge_table;
mod held_cells;
mod topology;
pub use edge_table::EdgeTable;
pub use topology::vertex_components;

#[cfg(test)]
mod tests;
