//! Linearly transformed cosines (Heitz, Dupuy, Hill & Neubelt 2016): the GGX lobe's
//! integral over a polygon in closed form, from the fitted table `ltc_ggx.json`
//! (`scripts/data/ltc_fit.py`), and the Beckmann lobe's (Mitsuba's exact models, separable
//! masking) from `ltc_beckmann.json` (`ltc_fit.py --distribution beckmann`). This is the CPU reference of `shaders/common/ltc.wgsl`,
//! written with the same steps in f32 (the parity test `tests/gpu_ltc.rs` holds the two
//! together), and the source of the table texture the shader reads ([`texture`]).
//!
//! For a shading point with normal n and view direction v, the polygon's corners
//! (relative to the point) are taken to the frame (t₁, t₂, n), t₁ the direction of v's
//! tangential part (the table is fitted with wo in the xz-plane, x ≥ 0), then by the
//! table's M⁻¹ (bilinear in roughness and θ_o); the transformed polygon is clipped to the
//! cosine's hemisphere z > 0 and its form factor E = Σ θᵢ·(n̂ᵢ)_z / 2π summed over its
//! edges (the horizon's arc counted as the edge between the points where the polygon
//! leaves and re-enters the hemisphere). ∫_P f·cos θi dω ≈ E·(F0·n + (1 − F0)·s) for a
//! Schlick Fresnel of reflectance F0 (n the lobe's albedo, s its Schlick moment; F0 = 1:
//! no Fresnel).

use crate::bsdf::microfacet::Distribution;
use glam::Vec3;
use std::f32::consts::TAU;
use std::sync::OnceLock;

/// The committed fits.
const TABLE_JSON: &str = include_str!("ltc_ggx.json");
const BECKMANN_JSON: &str = include_str!("ltc_beckmann.json");

#[derive(serde::Deserialize)]
struct CellJson {
    minv: [f64; 4],
    norm: f64,
    fresnel: f64,
}

#[derive(serde::Deserialize)]
struct TableJson {
    roughness: Vec<f64>,
    theta: Vec<f64>,
    cells: Vec<CellJson>,
}

/// One cell: M⁻¹'s entries [m00, m02, m20, m22] (m11 = 1, the others 0), the lobe's
/// albedo n and its Schlick moment s.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LtcCell {
    pub minv: [f32; 4],
    pub norm: f32,
    pub fresnel: f32,
}

impl LtcCell {
    fn lerp(self, o: LtcCell, t: f32) -> LtcCell {
        let l = |a: f32, b: f32| a + (b - a) * t;
        LtcCell {
            minv: std::array::from_fn(|k| l(self.minv[k], o.minv[k])),
            norm: l(self.norm, o.norm),
            fresnel: l(self.fresnel, o.fresnel),
        }
    }

    /// M⁻¹·w.
    pub fn apply(&self, w: Vec3) -> Vec3 {
        let m = self.minv;
        Vec3::new(m[0] * w.x + m[1] * w.z, w.y, m[2] * w.x + m[3] * w.z)
    }
}

/// The fitted table: `size`² cells, roughness linear over [`r0`, `r1`], θ_o linear over
/// [0, `theta_max`].
#[derive(Clone, Debug)]
pub struct LtcTable {
    pub size: usize,
    pub r0: f32,
    pub r1: f32,
    pub theta_max: f32,
    /// `cells[i * size + j]`: roughness i, θ j.
    pub cells: Vec<LtcCell>,
}

/// The committed GGX table (parsed once).
pub fn table() -> &'static LtcTable {
    static TABLE: OnceLock<LtcTable> = OnceLock::new();
    TABLE.get_or_init(|| parse(TABLE_JSON).expect("the committed LTC table parses"))
}

/// The committed table of `dist`'s lobe (parsed once).
pub fn table_of(dist: Distribution) -> &'static LtcTable {
    static BECKMANN: OnceLock<LtcTable> = OnceLock::new();
    match dist {
        Distribution::Ggx => table(),
        Distribution::Beckmann => BECKMANN
            .get_or_init(|| parse(BECKMANN_JSON).expect("the committed Beckmann LTC table parses")),
    }
}

/// Parses a table written by `ltc_fit.py`. Each cell's M⁻¹ is taken with m00 ≥ 0: the fit
/// is free to flip x (the cosine is symmetric in it, and the table scales M⁻¹ by |m11|
/// only), but the cells are interpolated entry by entry, so neighbours must agree.
fn parse(json: &str) -> Result<LtcTable, String> {
    let t: TableJson = serde_json::from_str(json).map_err(|e| e.to_string())?;
    let n = t.roughness.len();
    if n < 2 || t.theta.len() != n || t.cells.len() != n * n {
        return Err(format!(
            "LTC table: {n} roughness values, {} angles, {} cells",
            t.theta.len(),
            t.cells.len()
        ));
    }
    let cells = t
        .cells
        .iter()
        .map(|c| {
            let s = if c.minv[0] < 0.0 { -1.0 } else { 1.0 };
            LtcCell {
                minv: [
                    (s * c.minv[0]) as f32,
                    (s * c.minv[1]) as f32,
                    c.minv[2] as f32,
                    c.minv[3] as f32,
                ],
                norm: c.norm as f32,
                fresnel: c.fresnel as f32,
            }
        })
        .collect();
    Ok(LtcTable {
        size: n,
        r0: t.roughness[0] as f32,
        r1: t.roughness[n - 1] as f32,
        theta_max: t.theta[n - 1] as f32,
        cells,
    })
}

impl LtcTable {
    /// The cell at `roughness` and view cosine `cos_o`, bilinear between the nodes
    /// (clamped to the table's range).
    pub fn lookup(&self, roughness: f32, cos_o: f32) -> LtcCell {
        let last = (self.size - 1) as f32;
        let theta = cos_o.clamp(0.0, 1.0).acos();
        let fi = ((roughness - self.r0) / (self.r1 - self.r0) * last).clamp(0.0, last);
        let fj = (theta / self.theta_max * last).clamp(0.0, last);
        let i = (fi as usize).min(self.size - 2);
        let j = (fj as usize).min(self.size - 2);
        let (u, w) = (fi - i as f32, fj - j as f32);
        let c = |a: usize, b: usize| self.cells[a * self.size + b];
        let lo = c(i, j).lerp(c(i, j + 1), w);
        let hi = c(i + 1, j).lerp(c(i + 1, j + 1), w);
        lo.lerp(hi, u)
    }
}

/// The z part of Lambert's edge term θ·n̂ of the arc between unit vectors `a` and `b`.
fn edge_z(a: Vec3, b: Vec3) -> f32 {
    let c = a.cross(b);
    let s = c.length();
    if s <= 0.0 {
        return 0.0;
    }
    s.atan2(a.dot(b)) * (c.z / s)
}

/// The part of edge `p` → `q` above z = 0, its edge term added to `sum`; where the polygon
/// leaves the hemisphere the crossing goes to `exit`, where it re-enters to `entry`.
fn clip_edge(p: Vec3, q: Vec3, sum: &mut f32, exit: &mut Vec3, entry: &mut Vec3) {
    let (up, uq) = (p.z > 0.0, q.z > 0.0);
    if !up && !uq {
        return;
    }
    if up && uq {
        *sum += edge_z(p.normalize(), q.normalize());
        return;
    }
    let x = (p + (q - p) * (p.z / (p.z - q.z))).normalize();
    if up {
        *sum += edge_z(p.normalize(), x);
        *exit = x;
    } else {
        *sum += edge_z(x, q.normalize());
        *entry = x;
    }
}

/// The form factor of the polygon `corners` (a triangle repeats its first corner) clipped
/// to z > 0: |Σ θᵢ·(n̂ᵢ)_z| / 2π, the horizon's arc from the exit to the entry included.
pub fn form_factor(corners: &[Vec3]) -> f32 {
    let mut sum = 0.0;
    let mut exit = Vec3::ZERO;
    let mut entry = Vec3::ZERO;
    for k in 0..corners.len() {
        clip_edge(
            corners[k],
            corners[(k + 1) % corners.len()],
            &mut sum,
            &mut exit,
            &mut entry,
        );
    }
    sum += edge_z(exit, entry);
    sum.abs() / TAU
}

/// The shading frame's tangent t₁: v's tangential part, any tangent at normal view.
pub fn view_tangent(n: Vec3, v: Vec3) -> Vec3 {
    let t = v - n * n.dot(v);
    let l = t.length();
    if l > 1e-6 {
        return t / l;
    }
    let a = if n.x.abs() < 0.9 { Vec3::X } else { Vec3::Y };
    (a - n * n.dot(a)).normalize()
}

/// ∫ f·cos θi dω of the GGX lobe of `roughness` (α = roughness², Fresnel 1) over the
/// polygon `corners` (relative to the shading point, convex; a triangle may repeat its
/// first corner) seen from unit normal `n` and unit view direction `v`, and the same with
/// the Schlick weight (1 − wi·h)⁵: (E·n, E·s) of the module's header.
pub fn glossy_integral(n: Vec3, v: Vec3, roughness: f32, corners: &[Vec3]) -> [f32; 2] {
    glossy_integral_of(Distribution::Ggx, n, v, roughness, corners)
}

/// [`glossy_integral`] of `dist`'s lobe (Beckmann: Mitsuba's, separable masking).
pub fn glossy_integral_of(
    dist: Distribution,
    n: Vec3,
    v: Vec3,
    roughness: f32,
    corners: &[Vec3],
) -> [f32; 2] {
    let cell = table_of(dist).lookup(roughness, n.dot(v));
    let t1 = view_tangent(n, v);
    let t2 = n.cross(t1);
    let local: Vec<Vec3> = corners
        .iter()
        .map(|c| cell.apply(Vec3::new(c.dot(t1), c.dot(t2), c.dot(n))))
        .collect();
    let e = form_factor(&local);
    [e * cell.norm, e * cell.fresnel]
}

/// The corners, relative to the shading point, of the regular polygon that stands for a
/// sphere of `radius` at `centre` (relative to the point) in the direct pass
/// (`scene::emitters::round`, `round_lights.wgsl` `round_polygon`, the same steps): empty
/// from inside it.
pub fn sphere_polygon(centre: Vec3, radius: f32) -> Vec<Vec3> {
    use crate::scene::emitters::round::{polygon_scale, EDGES};
    let d2 = centre.length_squared();
    let r2 = radius * radius;
    if d2 <= r2 {
        return Vec::new();
    }
    let k = r2 / d2;
    let w = centre / d2.sqrt();
    let a = if w.x.abs() < 0.9 { Vec3::X } else { Vec3::Y };
    let u = a.cross(w).normalize();
    let scale = radius * (1.0 - k).sqrt() * polygon_scale();
    let mid = centre * (1.0 - k);
    let step = TAU / EDGES as f32;
    (0..EDGES)
        .map(|i| {
            let t = step * i as f32;
            mid + (u * t.cos() + w.cross(u) * t.sin()) * scale
        })
        .collect()
}

/// Texels per cell of [`LtcTable::texels`] (M⁻¹'s entries, then n and s).
pub const CELL_TEXELS: u32 = 2;

impl LtcTable {
    /// The table as the rows of an `Rgba32Float` texture `CELL_TEXELS·size` wide and
    /// `size + 1` high, the form `shaders/common/ltc.wgsl` reads (as Heitz et al. ship
    /// theirs: texels, not shader constants, so the shader compiles as a binding): row 0's
    /// first texel (r0, r1, θ_max, size), then one row per roughness i, two texels per θ j:
    /// M⁻¹'s entries, then (n, s, 0, 0).
    pub fn texels(&self) -> Vec<[f32; 4]> {
        let w = CELL_TEXELS as usize * self.size;
        let mut out = vec![[0.0; 4]; w * (self.size + 1)];
        out[0] = [self.r0, self.r1, self.theta_max, self.size as f32];
        for (k, c) in self.cells.iter().enumerate() {
            let at = w + CELL_TEXELS as usize * k;
            out[at] = c.minv;
            out[at + 1] = [c.norm, c.fresnel, 0.0, 0.0];
        }
        out
    }
}

/// The committed tables as the texels of one texture: GGX's rows ([`LtcTable::texels`]),
/// then Beckmann's (the shader's table 1 from row size + 1: the two are fitted on one grid
/// size, which the test of the tables checks).
pub fn all_texels() -> Vec<[f32; 4]> {
    let mut out = table().texels();
    out.extend(table_of(Distribution::Beckmann).texels());
    out
}

/// The committed tables as a texture on `ctx`'s device ([`all_texels`]), uploaded when
/// called (the direct pass makes it once per device).
pub fn texture(ctx: &crate::gpu::GpuContext) -> wgpu::Texture {
    let t = table();
    let size = (CELL_TEXELS * t.size as u32, 2 * (t.size as u32 + 1));
    crate::gpu::float_texture_of(ctx, "ltc table", size, &all_texels())
}

#[cfg(test)]
#[path = "ltc_tests.rs"]
mod tests;
