//! Materials: the interaction weights and parameters of a set of particles
//! (seed 000 eq. 11, seed 002 §4-5).
//!
//! A [`Material`] is plain data (serde, validated); [`Material::prepare`]
//! turns it into a [`PreparedMaterial`] with tables built and the set of
//! enabled terms fixed, which is what [`super::evaluate_pair`] reads.
//!
//! Default: cohesion spacing, every orientation weight 0 (a scene enables
//! the terms it uses), normalized terms, default repulsion, no friction,
//! no bonds.
//!
//! # Near coincidence
//!
//! The normalized co-planarity and co-circularity terms (and the normalized
//! spin potential) depend on `r` only through its direction `r/|r|`: they
//! have no limit at `r = 0` and their gradients grow like `1/|r|`. Where the
//! spacing core lets particles overlap (cohesion with a large `α`,
//! docs/model.md §7), a pair passing close to coincidence swept its direction through
//! half a turn within a few steps and the term's energy (up to `4 α ψ` per
//! side) jumped by whatever the step missed: a free shell of the first
//! `elastic_shell` preset (cohesion and co-circularity) gained energy by
//! bursts and tore apart at any
//! step size. These terms are therefore faded to zero below the
//! coincidence radius `r_near = NEAR_FRACTION · r_w` (`r_w` the bottom of
//! the spacing well, about `r0`; the weight's width `a` without spacing)
//! by the C2 quintic rise [`super::cutoff::smooth_rise`] of `|r|/r_near`,
//! so the energy, force and torque are continuous and bounded through
//! coincidence. Pairs at or beyond `r_near` (every pair of a material at
//! rest) are evaluated exactly as before. The raw terms, co-normality and
//! the form term are regular at `r = 0` and are not faded.

use super::cocircularity;
use super::conormality;
use super::coplanarity;
use super::cutoff::smooth_rise;
use super::form;
use super::lennard_jones::LennardJones;
use super::pair::{OrientationGrad, PairGeometry, TermGrad};
use super::repulsion::{Repulsion, RepulsionParams};
use super::spacing::{Spacing, SpacingKernel};
use super::spin::{self, SpinKind};
use super::weight::{Weight, WeightParams};
use crate::bond_memory::BondMemory;
use crate::bonds::BondParams;
use crate::error::{non_negative, ParamError};
use crate::heat::HeatResponse;
use crate::math::{Real, Vec3};
use crate::plasticity::Plasticity;
use serde::{Deserialize, Serialize};

/// The coincidence radius below which the normalized direction terms fade
/// to zero, as a fraction of the bottom of the spacing well `r_w` (of the
/// weight's width `a` without spacing); see the module docs.
pub const NEAR_FRACTION: Real = 0.25;

/// The interaction weights and parameters of a set of particles.
#[derive(Copy, Clone, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct Material {
    /// Spacing potential, or `None` for none. Default: cohesion with its
    /// defaults.
    pub spacing: Option<Spacing>,
    /// Orientation weight `ψ` (seed 000 eq. 10). Default: isotropic,
    /// `K = 1`, `a = 1`, cut-off 2.5.
    pub weight: WeightParams,
    /// Weight `α_P` of co-planarity (>= 0). Default: 0.
    #[schemars(range(min = 0))]
    pub coplanarity: Real,
    /// Weight `α_N` of co-normality (>= 0). Default: 0.
    #[schemars(range(min = 0))]
    pub conormality: Real,
    /// Weight `α_C` of co-circularity (>= 0). Default: 0.
    #[schemars(range(min = 0))]
    pub cocircularity: Real,
    /// Weight `α_F` of the form (shape memory) term (>= 0). Default: 0.
    #[schemars(range(min = 0))]
    pub form: Real,
    /// Weight `α_S` of the spin torque (>= 0). Default: 0.
    #[schemars(range(min = 0))]
    pub spin: Real,
    /// Which spin potential. Default: `MinCurvature` (seed 000 eq. 14).
    pub spin_kind: SpinKind,
    /// Use the normalized (dimensionless, roughly scale independent)
    /// orientation terms (docs/model.md §3). Default: true.
    pub normalized: bool,
    /// Exponential repulsion for pairs that do not interact completely.
    /// Default: strength 1 at contact distance 1, decay 0.1, cut-off 2.
    pub repulsion: RepulsionParams,
    /// Inter-particle friction coefficient (>= 0; damping of relative
    /// velocity, seed 002 §5, applied by the world). Default: 0.
    #[schemars(range(min = 0))]
    pub friction: Real,
    /// How heat weakens this material's bonds ([`crate::heat`]), or `None`
    /// for not at all. Default: `None`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub heat: Option<HeatResponse>,
    /// Explicit bonds ([`crate::bonds`]): pairs of one object within
    /// `radius` when the world is built interact completely, other pairs
    /// of the object only repel, and a bond stretched beyond
    /// `break_length` breaks for good (seed 000 fig. 12a, 12c). `None`:
    /// every pair of one object within the cut-off interacts completely.
    /// Default: `None`.
    pub bonds: Option<BondParams>,
    /// Plasticity of the remembered curvature (seed 000 fig. 12b, see
    /// [`crate::plasticity`]); needs `form > 0`. Default: none (elastic).
    pub plasticity: Option<Plasticity>,
    /// Bond memory ([`crate::bond_memory`]): each bonded partner's offset
    /// in the particle's own frame, held by a spring and, with a `flow`,
    /// flowing beyond a yield (a plastic lattice, seed 000 fig. 12b);
    /// needs `bonds`. Default: none.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub bond_memory: Option<BondMemory>,
}

impl Default for Material {
    fn default() -> Self {
        Material {
            spacing: Some(Spacing::default()),
            weight: WeightParams::default(),
            coplanarity: 0.0,
            conormality: 0.0,
            cocircularity: 0.0,
            form: 0.0,
            spin: 0.0,
            spin_kind: SpinKind::default(),
            normalized: true,
            repulsion: RepulsionParams::default(),
            friction: 0.0,
            heat: None,
            bonds: None,
            plasticity: None,
            bond_memory: None,
        }
    }
}

impl Material {
    /// A material with no term enabled: no spacing, zero weights, zero
    /// repulsion strength (a base to enable terms one by one).
    pub fn empty() -> Self {
        Material {
            spacing: None,
            repulsion: RepulsionParams {
                strength: 0.0,
                ..Default::default()
            },
            ..Default::default()
        }
    }

    /// Rejects NaN, infinite and out-of-range values; the message names the
    /// field path (e.g. `spacing.cohesion.alpha`, `weight.b`, `form`).
    pub fn validate(&self) -> Result<(), ParamError> {
        if let Some(s) = &self.spacing {
            s.validate().map_err(|e| e.within("spacing"))?;
        }
        self.weight.validate().map_err(|e| e.within("weight"))?;
        non_negative("coplanarity", self.coplanarity)?;
        non_negative("conormality", self.conormality)?;
        non_negative("cocircularity", self.cocircularity)?;
        non_negative("form", self.form)?;
        non_negative("spin", self.spin)?;
        self.repulsion
            .validate()
            .map_err(|e| e.within("repulsion"))?;
        non_negative("friction", self.friction)?;
        if let Some(h) = &self.heat {
            h.validate().map_err(|e| e.within("heat"))?;
        }
        if let Some(b) = &self.bonds {
            b.validate().map_err(|e| e.within("bonds"))?;
        }
        if let Some(p) = &self.plasticity {
            p.validate().map_err(|e| e.within("plasticity"))?;
            if self.form == 0.0 {
                return Err(ParamError::Invalid {
                    field: "plasticity".into(),
                    message: "acts on the form term's rest curvature: needs form > 0".into(),
                });
            }
        }
        if let Some(m) = &self.bond_memory {
            m.validate().map_err(|e| e.within("bond_memory"))?;
            if self.bonds.is_none() {
                return Err(ParamError::Invalid {
                    field: "bond_memory".into(),
                    message: "remembers the offsets of bonded partners: needs bonds, \
                              e.g. bonds: (radius: 1.5)"
                        .into(),
                });
            }
        }
        Ok(())
    }

    /// Validates and precomputes (weight constants, cohesion tables).
    pub fn prepare(&self) -> Result<PreparedMaterial, ParamError> {
        self.validate()?;
        let spacing = match &self.spacing {
            Some(s) => Some(s.prepare().map_err(|e| e.within("spacing"))?),
            None => None,
        };
        let oriented = self.coplanarity > 0.0
            || self.conormality > 0.0
            || self.cocircularity > 0.0
            || self.form > 0.0
            || self.spin > 0.0;
        let well = spacing.as_ref().map_or((0.0, 0.0), SpacingKernel::well);
        let near = NEAR_FRACTION
            * if spacing.is_some() {
                well.0
            } else {
                self.weight.a
            };
        Ok(PreparedMaterial {
            well,
            near,
            spacing,
            weight: self.weight.prepare().map_err(|e| e.within("weight"))?,
            w_p: self.coplanarity,
            w_n: self.conormality,
            w_c: self.cocircularity,
            w_f: self.form,
            w_s: self.spin,
            spin_kind: self.spin_kind,
            normalized: self.normalized,
            oriented,
            repulsion: self
                .repulsion
                .prepare()
                .map_err(|e| e.within("repulsion"))?,
            friction: self.friction,
            bonds: self.bonds,
            source: *self,
        })
    }
}

/// One direction of the fused pair kernel
/// ([`PreparedMaterial::direction`]).
#[derive(Copy, Clone, Debug, Default, PartialEq)]
pub(crate) struct Direction {
    pub energy: Real,
    pub g_r: Real,
    pub g_e: Real,
    pub g_n: Real,
    pub b: Real,
}

/// A validated material with its tables built and its enabled terms fixed.
#[derive(Clone, Debug, PartialEq)]
pub struct PreparedMaterial {
    spacing: Option<SpacingKernel>,
    /// Position and value of the spacing potential's minimum.
    well: (Real, Real),
    /// The coincidence radius `r_near` (module docs).
    near: Real,
    weight: Weight,
    w_p: Real,
    w_n: Real,
    w_c: Real,
    w_f: Real,
    w_s: Real,
    spin_kind: SpinKind,
    normalized: bool,
    oriented: bool,
    repulsion: Repulsion,
    friction: Real,
    bonds: Option<BondParams>,
    source: Material,
}

impl PreparedMaterial {
    /// The material this was prepared from.
    pub fn material(&self) -> &Material {
        &self.source
    }

    /// The spacing potential, if any.
    pub fn spacing(&self) -> Option<&SpacingKernel> {
        self.spacing.as_ref()
    }

    /// The spacing potential when it is 12-6 Lennard-Jones (the potential
    /// of the SIMD and cluster kernels).
    #[inline]
    pub fn lennard_jones_12_6(&self) -> Option<&LennardJones> {
        match &self.spacing {
            Some(SpacingKernel::LennardJones(l)) if l.is_12_6() => Some(l),
            _ => None,
        }
    }

    /// True when some orientation term (co-planarity, co-normality,
    /// co-circularity, form, spin) has a nonzero weight.
    #[inline]
    pub fn has_orientation_terms(&self) -> bool {
        self.oriented
    }

    /// Spacing cut-off, or 0 without spacing.
    pub fn spacing_cutoff(&self) -> Real {
        self.spacing.as_ref().map_or(0.0, SpacingKernel::cutoff)
    }

    /// Cut-off of the orientation weight, or 0 without orientation terms.
    #[inline]
    pub fn orientation_cutoff(&self) -> Real {
        if self.oriented {
            self.weight.cutoff()
        } else {
            0.0
        }
    }

    /// Repulsion cut-off, or 0 when the repulsion strength is 0.
    pub fn repulsion_cutoff(&self) -> Real {
        if self.repulsion.is_enabled() {
            self.repulsion.cutoff()
        } else {
            0.0
        }
    }

    /// The largest cut-off among the enabled terms (spacing, orientation
    /// weight, repulsion): the neighbour radius this material needs.
    pub fn cutoff(&self) -> Real {
        self.spacing_cutoff()
            .max(self.orientation_cutoff())
            .max(self.repulsion_cutoff())
    }

    /// Names of the enabled terms, e.g. `["cohesion", "coplanarity",
    /// "form", "repulsion"]`.
    pub fn enabled_terms(&self) -> Vec<&'static str> {
        let mut v = Vec::new();
        if let Some(s) = &self.spacing {
            v.push(s.name());
        }
        for (w, name) in [
            (self.w_p, "coplanarity"),
            (self.w_n, "conormality"),
            (self.w_c, "cocircularity"),
            (self.w_f, "form"),
            (self.w_s, "spin"),
        ] {
            if w > 0.0 {
                v.push(name);
            }
        }
        if self.repulsion.is_enabled() {
            v.push("repulsion");
        }
        if self.bonds.is_some() {
            v.push("bonds");
        }
        if self.source.plasticity.is_some() {
            v.push("plasticity");
        }
        if self.source.bond_memory.is_some() {
            v.push("bond_memory");
        }
        v
    }

    /// The bond memory, if any ([`crate::bond_memory`]).
    #[inline]
    pub fn bond_memory(&self) -> Option<&BondMemory> {
        self.source.bond_memory.as_ref()
    }

    /// Plasticity of the remembered curvature, if any.
    #[inline]
    pub fn plasticity(&self) -> Option<&Plasticity> {
        self.source.plasticity.as_ref()
    }

    /// The orientation weight `ψ` (seed 000 eq. 10) this material's
    /// particle `i` gives the pair `r = p_j - p_i` at `dist = |r| > 0`,
    /// with `i`'s normal `n_i` (zero at and beyond the cut-off).
    #[inline]
    pub fn orientation_weight(&self, r: &Vec3, dist: Real, n_i: &Vec3) -> Real {
        self.weight.eval(r, dist, n_i).psi
    }

    /// Inter-particle friction coefficient (applied by the world).
    pub fn friction(&self) -> Real {
        self.friction
    }

    /// The bond rule, if this material is bonded ([`crate::bonds`]).
    #[inline]
    pub fn bonds(&self) -> Option<&BondParams> {
        self.bonds.as_ref()
    }

    /// This material's spacing potential as `(U(r), U'(r)/r)` from
    /// `d2 = r²` and `inv_d2 = 1/r²` ([`SpacingKernel::eval_sq`]); zero
    /// without spacing.
    #[inline(always)]
    pub fn spacing_eval_sq(&self, d2: Real, inv_d2: Real) -> (Real, Real) {
        match &self.spacing {
            Some(s) => s.eval_sq(d2, inv_d2),
            None => (0.0, 0.0),
        }
    }

    /// The orientation weight `ψ`'s parameters.
    #[inline]
    pub fn weight(&self) -> &Weight {
        &self.weight
    }

    /// True when the spin torque is on.
    #[inline]
    pub(crate) fn has_spin(&self) -> bool {
        self.w_s > 0.0
    }

    /// The spin torque on the emitter of `g` under the weight `psi`
    /// (already weakened by heat, if any).
    #[inline]
    pub(crate) fn spin_torque(&self, g: &PairGeometry, psi: Real) -> Vec3 {
        let s = spin::eval(self.spin_kind, self.normalized, g);
        // A rotation about n_i leaves |r| unchanged: the fade only scales.
        let f = self.near_fade(g.dist).map_or(1.0, |(f, _)| f);
        spin::torque(&g.n_i, &g.t_i, &(s.d_t * (self.w_s * psi * f)))
    }

    /// One direction of the fused pair kernel ([`super::pair`]): the
    /// orientation energy `E = ψ Φ` this material's emitter `e` gives the
    /// pair, and the scalars of its gradients, in the emitter's frame
    /// (`r_e = p_receiver - p_e`):
    ///
    /// - `∂E/∂r_e = g_r r_e + g_e n_e + g_n n_r`;
    /// - torque on the emitter `g_e (r_e × n_e) + b (n_e × n_r)`;
    /// - torque on the receiver `g_n (r_e × n_r) - b (n_e × n_r)`.
    ///
    /// Every term of [`Self::orientation`] (spin excepted) reduces to
    /// these five scalars: `∂Φ/∂n_e = A r_e + B (n_e - n_r)` and
    /// `∂Φ/∂n_r = C r_e - B (n_e - n_r)`, where `A` and `C` are also the
    /// `n_e` and `n_r` coefficients of `∂Φ/∂r_e`, and `n × n = 0` removes
    /// the rest from the torques. Inputs: `d2 = |r|²`, `inv_d2`,
    /// `z_e = n_e·r_e`, `z_r = n_r·r_e`, `dd = |n_e - n_r|²`; `r` and
    /// `d = ±(n_e - n_r)` with the sign of `r_e` (only `|κ r_e + n_e - n_r|`
    /// is read from them, for the form term), the emitter's curvature, and
    /// its weight `(ψ, w_r, w_n)` ([`Weight::eval_scalar`]).
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    pub(crate) fn direction(
        &self,
        dist: Real,
        inv_d2: Real,
        z_e: Real,
        z_r: Real,
        dd: Real,
        r: &Vec3,
        d: &Vec3,
        kappa: Real,
        (psi, wr, wn): (Real, Real, Real),
    ) -> Direction {
        let pn = if self.normalized { inv_d2 } else { 1.0 };
        let c = z_e + z_r;
        let phi_p = z_e * z_e * pn;
        let phi_c = c * c * pn;
        let (a_f, v2) = if self.w_f > 0.0 {
            // The raw form term is the normalized one over κ² (zero for
            // κ = 0).
            let a_f = if self.normalized {
                self.w_f
            } else if kappa == 0.0 {
                0.0
            } else {
                self.w_f / (kappa * kappa)
            };
            (a_f, (r * kappa + d).norm_squared())
        } else {
            (0.0, 0.0)
        };
        // The normalized direction terms fade out near coincidence (module
        // docs, "Near coincidence"): `(S, S')`, exactly `(1, 0)` at and
        // beyond `r_near`, where every product below is unchanged.
        let (fs, fds) = self.near_fade(dist).unwrap_or((1.0, 0.0));
        let pc = self.w_p * phi_p + self.w_c * phi_c;
        let phi = fs * (self.w_p * phi_p) + self.w_n * dd + fs * (self.w_c * phi_c) + a_f * v2;
        let nr = if self.normalized { inv_d2 } else { 0.0 };
        // `∂(S Φ)/∂r = S ∂Φ/∂r + Φ S' r/|r|`: the second part is along `r`.
        let rr = 2.0 * (a_f * kappa * kappa - nr * (fs * pc)) + fds * pc * (dist * inv_d2);
        let rc = 2.0 * pn * self.w_c * c * fs;
        let rf = 2.0 * a_f * kappa;
        let rne = 2.0 * pn * self.w_p * z_e * fs + rc + rf;
        let rnr = rc - rf;
        Direction {
            energy: psi * phi,
            g_r: psi * rr + phi * wr,
            g_e: psi * rne + phi * wn,
            g_n: psi * rnr,
            b: psi * (2.0 * (self.w_n + a_f)),
        }
    }

    /// The constants of the oriented SIMD lanes (`lanes.rs`), which
    /// evaluate [`Self::direction`] of both directions of a pair of this
    /// material with 12-6 Lennard-Jones spacing; `None` when the material
    /// has another spacing (or none), no orientation term, or spin (the
    /// scalar kernel evaluates those).
    pub(crate) fn oriented_lane_constants(&self) -> Option<crate::lanes::OrientedLaneConstants> {
        let lj = match &self.spacing {
            Some(SpacingKernel::LennardJones(l)) if l.is_12_6() => l.lane_constants(),
            _ => return None,
        };
        (self.oriented && !self.has_spin()).then(|| crate::lanes::OrientedLaneConstants {
            lj,
            weight: self.weight.lane_constants(),
            normalized: self.normalized,
            w_p: self.w_p,
            w_n: self.w_n,
            w_c: self.w_c,
            w_f: self.w_f,
            near: self.near,
        })
    }

    /// This material's spacing potential `(U(r), dU/dr)` (not halved);
    /// zero without spacing.
    #[inline]
    pub fn spacing_eval(&self, dist: Real) -> (Real, Real) {
        match &self.spacing {
            Some(s) => s.eval(dist),
            None => (0.0, 0.0),
        }
    }

    /// `(r_w, U(r_w))`, the bottom of the spacing well (`(0, 0)` without
    /// spacing); heat weakening keeps the core below `r_w`.
    #[inline]
    pub fn spacing_well(&self) -> (Real, Real) {
        self.well
    }

    /// How heat weakens this material, if it does.
    #[inline]
    pub fn heat_response(&self) -> Option<&HeatResponse> {
        self.source.heat.as_ref()
    }

    /// This material's repulsion `(U(r), dU/dr)` (not halved).
    #[inline]
    pub fn repulsion_eval(&self, dist: Real) -> (Real, Real) {
        self.repulsion.eval(dist)
    }

    /// The weighted orientation energy `E_ij` emitted by this material's
    /// particle `i` and felt by `j`, its gradients, and the spin torque on
    /// `i`. Zero-weight terms are skipped.
    #[inline]
    pub fn orientation(&self, g: &PairGeometry) -> OrientationGrad {
        let mut out = OrientationGrad::default();
        if !self.oriented {
            return out;
        }
        let w = self.weight.eval(&g.r, g.dist, &g.n_i);
        if w.psi == 0.0 {
            return out;
        }
        let mut phi = TermGrad::default();
        let norm = self.normalized;
        // Fade of the normalized direction terms near coincidence (module
        // docs); `None` at and beyond `r_near`, where nothing changes.
        let fade = self.near_fade(g.dist);
        if self.w_p > 0.0 {
            let t = if norm {
                faded(coplanarity::normalized(g), fade, g)
            } else {
                coplanarity::raw(g)
            };
            phi.add_scaled(self.w_p, &t);
        }
        if self.w_n > 0.0 {
            phi.add_scaled(self.w_n, &conormality::eval(g));
        }
        if self.w_c > 0.0 {
            let t = if norm {
                faded(cocircularity::normalized(g), fade, g)
            } else {
                cocircularity::raw(g)
            };
            phi.add_scaled(self.w_c, &t);
        }
        if self.w_f > 0.0 {
            let t = if norm {
                form::normalized(g)
            } else {
                form::raw(g)
            };
            phi.add_scaled(self.w_f, &t);
        }
        out.energy = w.psi * phi.energy;
        out.d_r = phi.d_r * w.psi + w.d_r * phi.energy;
        out.d_ni = phi.d_ni * w.psi + w.d_n * phi.energy;
        out.d_nj = phi.d_nj * w.psi;
        if self.w_s > 0.0 {
            let s = spin::eval(self.spin_kind, norm, g);
            // A rotation about n_i leaves |r| unchanged: the fade only scales.
            let f = fade.map_or(1.0, |(f, _)| f);
            out.spin_torque = spin::torque(&g.n_i, &g.t_i, &(s.d_t * (self.w_s * w.psi * f)));
        }
        out
    }

    /// The weighted spin energy `α_S φ_S ψ` emitted by `i` (diagnostics;
    /// not part of the pair energy, see [`super::spin`]).
    pub fn spin_energy(&self, g: &PairGeometry) -> Real {
        if self.w_s == 0.0 {
            return 0.0;
        }
        let w = self.weight.eval(&g.r, g.dist, &g.n_i);
        let f = self.near_fade(g.dist).map_or(1.0, |(f, _)| f);
        self.w_s * w.psi * f * spin::eval(self.spin_kind, self.normalized, g).energy
    }

    /// The coincidence radius `r_near` below which the normalized direction
    /// terms fade to zero (module docs).
    pub fn near_radius(&self) -> Real {
        self.near
    }

    /// `Some((S, dS/dr))`, the fade of the normalized direction terms at
    /// `dist < r_near`; `None` for the raw terms or at and beyond `r_near`.
    #[inline]
    fn near_fade(&self, dist: Real) -> Option<(Real, Real)> {
        if self.normalized && dist < self.near {
            let (s, ds) = smooth_rise(dist / self.near);
            Some((s, ds / self.near))
        } else {
            None
        }
    }
}

/// A direction term `φ(r/|r|, n_i, n_j)` multiplied by the fade `S(|r|)`:
/// `∂(Sφ)/∂r = S ∂φ/∂r + φ S' r/|r|`. Unchanged for `fade == None`.
#[inline]
fn faded(t: TermGrad, fade: Option<(Real, Real)>, g: &PairGeometry) -> TermGrad {
    match fade {
        None => t,
        Some((s, ds)) => TermGrad {
            energy: t.energy * s,
            d_r: t.d_r * s + g.r * (t.energy * ds / g.dist),
            d_ni: t.d_ni * s,
            d_nj: t.d_nj * s,
        },
    }
}

#[cfg(test)]
mod tests;
