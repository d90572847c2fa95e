//! `EXT_lights_ies`: point lights whose intensity varies with direction as an IES LM-63
//! photometric profile says (the data sheets luminaire makers publish). The extension's
//! text fixes the frame: the profile's (0°, 0°) point, where the luminaire aims, is the
//! node's −Z, and the X/Z plane is the vertical photometric plane (horizontal angle 0).
//!
//! - Type C (architectural lighting): horizontal angles turn counter-clockwise about +Z,
//!   from +X toward +Y. A direction of vertical angle θ and horizontal angle φ is
//!   (sin θ cos φ, sin θ sin φ, −cos θ).
//! - Type B (floodlights, the extension asks for it too): the photometric web's polar
//!   axis is the luminaire's lateral one (±Y here). A vertical angle V tilts the plane
//!   of the horizontal angles about that axis, from the aim toward +X; the horizontal
//!   angle H leaves the aim within that plane, clockwise seen from +X as the extension
//!   says of Type B, so toward −Y. A direction of angles (V, H) is
//!   (cos H sin V, −sin H, −cos H cos V), and only the hemisphere the lamp faces is lit.
//!
//! The file's candela table is interpolated bilinearly in its own two angles, as
//! lighting tools do. Its symmetry (Type C, one angle: round; 0–90°: each quadrant
//! alike; 0–180° or 90–270°: mirrored across a plane; Type B, 0–90°: mirrored across the
//! vertical plane) is unfolded here, so the kernel (`inc/lights.glsl`,
//! `punctual_profile`) looks up one table whatever the file's symmetry. Outside the
//! measured angles the light is dark (a 0–90° Type C profile lights only the half-space
//! it faces). Type A (automotive, optional in the extension) is refused by name.

use std::f32::consts::{FRAC_PI_2, TAU};

/// The extension's name.
pub(super) const EXTENSION: &str = "EXT_lights_ies";

/// The media type a profile in a buffer view must declare.
const MIME_TYPE: &str = "application/x-ies-lm-63";

/// The stand-in grid's rows (uniform in the cosine of the vertical angle) and columns (horizontal angles, 0
/// to 2π); the kernel's `punctual_profile_bound` indexes it with the same numbers.
pub const BOUND_ROWS: usize = 16;
pub const BOUND_COLUMNS: usize = 32;

/// `PunctualLight::profile`'s bit that marks a mirrored frame (the node's transform has a
/// negative determinant); the bits below it are the profile's offset.
pub const PROFILE_MIRRORED: u32 = 1 << 31;

/// The offset of light `l`'s profile in the scene's profile array, None without one.
pub fn profile_offset(l: &crate::gpu::PunctualLight) -> Option<usize> {
    (l.profile != crate::gpu::INVALID_INDEX).then_some((l.profile & !PROFILE_MIRRORED) as usize)
}

/// The most candela values a profile may have (a 1° web over the sphere has 65,341).
const MAX_VALUES: usize = 1 << 20;

/// How a profile's two angles lie on the sphere: LM-63's photometric type (the module's
/// text gives both frames).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Photometry {
    /// Vertical angle from the aim, horizontal angle about it.
    TypeC,
    /// Vertical angle tilting a plane about the lateral axis, horizontal angle within it.
    TypeB,
}

/// `pack`'s bit on the horizontal-angle count that marks a Type B profile.
const TYPE_B_BIT: u32 = 1 << 31;

/// A profile with its symmetry unfolded: Type C over horizontal angles 0–360°, Type B
/// over the horizontal angles on both sides of the vertical plane.
#[derive(Clone, Debug, PartialEq)]
pub struct IesProfile {
    /// The frame of the angles below.
    pub photometry: Photometry,
    /// Vertical angles in radians, increasing: θ within [0, π] (Type C), V within
    /// [−π/2, π/2] (Type B).
    pub vertical: Vec<f32>,
    /// Horizontal angles in radians, increasing: φ from 0 to 2π, or one entry for a
    /// round profile (Type C); H within [−π/2, π/2] (Type B).
    pub horizontal: Vec<f32>,
    /// Candela (the file's values times its candela multiplier and ballast factors),
    /// `candela[h * vertical.len() + v]`.
    pub candela: Vec<f32>,
}

/// Which half of the horizontal angles a file gives, by the symmetry they imply.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Symmetry {
    Round,
    Quadrant,
    Bilateral0,
    Bilateral90,
    Full,
}

/// Reads an LM-63 profile (1986, 1991, 1995, 2002 or 2019), returning it and what was
/// ignored (`TILT` data, which the extension does not ask for). Type C and Type B
/// photometry.
pub fn parse(bytes: &[u8]) -> Result<(IesProfile, Vec<String>), String> {
    let text = String::from_utf8_lossy(bytes);
    let mut warnings = Vec::new();
    let mut lines = text.lines();
    let mut tilt = None;
    for line in lines.by_ref() {
        if let Some(rest) = line.trim_start().strip_prefix("TILT=") {
            tilt = Some(rest.trim().to_string());
            break;
        }
    }
    let tilt = tilt.ok_or("no `TILT=` line: not an IES LM-63 profile")?;
    let rest: String = lines.collect::<Vec<_>>().join("\n");
    let mut tokens = rest
        .split(|c: char| c.is_whitespace() || c == ',')
        .filter(|t| !t.is_empty());
    let mut number = |what: &str| -> Result<f64, String> {
        let t = tokens
            .next()
            .ok_or_else(|| format!("ends before its {what}"))?;
        let v: f64 = t
            .parse()
            .map_err(|_| format!("its {what} `{t}` is not a number"))?;
        if !v.is_finite() {
            return Err(format!("its {what} is not finite"));
        }
        Ok(v)
    };
    match tilt.as_str() {
        "NONE" => {}
        "INCLUDE" => {
            number("tilt geometry")?;
            let n = count(number("tilt angle count")?, "tilt angle count")?;
            for _ in 0..2 * n {
                number("tilt data")?;
            }
            warnings.push("its TILT data is ignored (the lamp is taken as measured)".into());
        }
        other => warnings.push(format!(
            "its tilt file `{other}` is not read (the lamp is taken as measured)"
        )),
    }
    let _lamps = number("number of lamps")?;
    let _lumens = number("lumens per lamp")?;
    let multiplier = number("candela multiplier")?;
    let nv = count(
        number("number of vertical angles")?,
        "number of vertical angles",
    )?;
    let nh = count(
        number("number of horizontal angles")?,
        "number of horizontal angles",
    )?;
    let photometric_type = number("photometric type")?;
    for what in ["units type", "width", "length", "height"] {
        number(what)?;
    }
    let ballast = number("ballast factor")?;
    let ballast_lamp = number("ballast-lamp photometric factor")?;
    let _watts = number("input watts")?;
    if nv == 0 || nh == 0 || nv.saturating_mul(nh) > MAX_VALUES {
        return Err(format!(
            "has {nv} × {nh} candela values (1 to {MAX_VALUES} allowed)"
        ));
    }
    let photometry = match photometric_type as i64 {
        1 => Photometry::TypeC,
        2 => Photometry::TypeB,
        3 => {
            return Err(
                "uses Type A (3) photometry (automotive); lanterna reads Type C (1) and \
                 Type B (2)"
                    .into(),
            )
        }
        _ => {
            return Err(format!(
                "has photometric type {photometric_type}, not 1, 2 or 3"
            ))
        }
    };
    let scale = multiplier * ballast * ballast_lamp;
    if scale < 0.0 {
        return Err("has a negative candela multiplier or ballast factor".into());
    }
    let vertical = (0..nv)
        .map(|_| number("vertical angles"))
        .collect::<Result<Vec<_>, _>>()?;
    let horizontal = (0..nh)
        .map(|_| number("horizontal angles"))
        .collect::<Result<Vec<_>, _>>()?;
    let mut candela = Vec::with_capacity(nv * nh);
    for _ in 0..nv * nh {
        let c = number("candela values")?;
        if c < 0.0 {
            return Err(format!("has a negative candela value ({c})"));
        }
        candela.push(c * scale);
    }
    increasing(&vertical, "vertical")?;
    increasing(&horizontal, "horizontal")?;
    let profile = match photometry {
        Photometry::TypeC => {
            if vertical[0] < 0.0 || vertical[nv - 1] > 180.0 {
                return Err(format!(
                    "has vertical angles {}°–{}°, outside Type C's 0°–180°",
                    vertical[0],
                    vertical[nv - 1]
                ));
            }
            let symmetry = symmetry(&horizontal)?;
            unfold(&vertical, &horizontal, &candela, symmetry)
        }
        Photometry::TypeB => {
            let mirrored = symmetric_b(&vertical, &horizontal)?;
            unfold_b(&vertical, &horizontal, &candela, mirrored)
        }
    };
    if profile.candela.iter().any(|c| !c.is_finite()) {
        return Err("has candela values beyond single precision".into());
    }
    Ok((profile, warnings))
}

fn count(v: f64, what: &str) -> Result<usize, String> {
    if v.fract() != 0.0 || !(0.0..=MAX_VALUES as f64).contains(&v) {
        return Err(format!(
            "its {what} ({v}) is not a count up to {MAX_VALUES}"
        ));
    }
    Ok(v as usize)
}

fn increasing(angles: &[f64], which: &str) -> Result<(), String> {
    match angles.windows(2).find(|w| w[1] <= w[0]) {
        Some(w) => Err(format!(
            "its {which} angles do not increase ({}° then {}°)",
            w[0], w[1]
        )),
        None => Ok(()),
    }
}

/// The symmetry Type C's first and last horizontal angles imply (LM-63; 1995's
/// 90°–270° included, as the extension asks).
fn symmetry(h: &[f64]) -> Result<Symmetry, String> {
    const EPS: f64 = 1e-3;
    let (first, last) = (h[0], h[h.len() - 1]);
    let near = |a: f64, b: f64| (a - b).abs() < EPS;
    Ok(if h.len() == 1 {
        Symmetry::Round
    } else if near(first, 0.0) && near(last, 90.0) {
        Symmetry::Quadrant
    } else if near(first, 0.0) && near(last, 180.0) {
        Symmetry::Bilateral0
    } else if near(first, 90.0) && near(last, 270.0) {
        Symmetry::Bilateral90
    } else if near(first, 0.0) && last > 180.0 && last <= 360.0 + EPS {
        Symmetry::Full
    } else {
        return Err(format!(
            "has horizontal angles {first}°–{last}°; Type C asks for one angle, 0–90°, \
             0–180°, 90–270° or 0–360°"
        ));
    })
}

/// The profile over 0–360°: every horizontal angle's images under the symmetry, each
/// with the column of the angle it mirrors; where the images leave a gap across 0°
/// (90–270° files, full files that stop short of 360°), the ends are the columns
/// interpolated across it.
fn unfold(vertical: &[f64], horizontal: &[f64], candela: &[f64], s: Symmetry) -> IesProfile {
    let nv = vertical.len();
    let column = |i: usize| candela[i * nv..(i + 1) * nv].to_vec();
    let mut columns: Vec<(f64, Vec<f64>)> = Vec::new();
    for (i, &h) in horizontal.iter().enumerate() {
        let images: &[f64] = match s {
            Symmetry::Round => &[0.0],
            Symmetry::Quadrant => &[h, 180.0 - h, 180.0 + h, 360.0 - h],
            Symmetry::Bilateral0 => &[h, 360.0 - h],
            Symmetry::Bilateral90 => &[h, (540.0 - h) % 360.0],
            Symmetry::Full => &[h.min(360.0)],
        };
        columns.extend(images.iter().map(|&a| (a, column(i))));
    }
    columns.sort_by(|a, b| a.0.total_cmp(&b.0));
    columns.dedup_by(|b, a| (b.0 - a.0).abs() < 1e-3);
    if s != Symmetry::Round {
        let (first, last) = (columns[0].0, columns[columns.len() - 1].0);
        if first > 1e-3 || last < 360.0 - 1e-3 {
            // 0° and 360° are one direction: interpolate across the gap [last, first + 360].
            let t = (360.0 - last) / (first + 360.0 - last);
            let end: Vec<f64> = columns[columns.len() - 1]
                .1
                .iter()
                .zip(&columns[0].1)
                .map(|(a, b)| a * (1.0 - t) + b * t)
                .collect();
            if first > 1e-3 {
                columns.insert(0, (0.0, end.clone()));
            }
            if last < 360.0 - 1e-3 {
                columns.push((360.0, end));
            }
        }
    }
    let columns: Vec<(f64, &[f64])> = columns.iter().map(|(a, c)| (*a, c.as_slice())).collect();
    from_columns(Photometry::TypeC, vertical, &columns)
}

/// The profile of `vertical` angles and (horizontal angle, candela column) pairs, all
/// in degrees, in the kernel's units (radians, single precision).
fn from_columns(photometry: Photometry, vertical: &[f64], columns: &[(f64, &[f64])]) -> IesProfile {
    IesProfile {
        photometry,
        vertical: vertical.iter().map(|a| a.to_radians() as f32).collect(),
        horizontal: columns.iter().map(|c| c.0.to_radians() as f32).collect(),
        candela: columns
            .iter()
            .flat_map(|c| c.1.iter().map(|&x| x as f32))
            .collect(),
    }
}

/// Whether a Type B file's horizontal angles imply a luminaire symmetric across its
/// vertical plane (LM-63: 0–90° then, −90–90° otherwise; a narrower span is dark beyond
/// it), after checking that both angles stay on the hemisphere the lamp faces.
fn symmetric_b(v: &[f64], h: &[f64]) -> Result<bool, String> {
    if v.len() < 2 || h.len() < 2 {
        return Err(format!(
            "has {} vertical and {} horizontal angles; Type B needs two of each at least",
            v.len(),
            h.len()
        ));
    }
    for (angles, which) in [(v, "vertical"), (h, "horizontal")] {
        let (first, last) = (angles[0], angles[angles.len() - 1]);
        if first < -90.0 || last > 90.0 {
            return Err(format!(
                "has {which} angles {first}°–{last}°, outside Type B's −90°–90°"
            ));
        }
    }
    Ok(h[0] == 0.0)
}

/// A Type B profile over both sides of its vertical plane: a 0–90° file's columns
/// mirrored to −H.
fn unfold_b(vertical: &[f64], horizontal: &[f64], candela: &[f64], mirrored: bool) -> IesProfile {
    let nv = vertical.len();
    let mut columns: Vec<(f64, &[f64])> = horizontal
        .iter()
        .enumerate()
        .map(|(i, &h)| (h, &candela[i * nv..(i + 1) * nv]))
        .collect();
    if mirrored {
        let mirrored: Vec<_> = columns[1..].iter().map(|&(h, c)| (-h, c)).collect();
        columns.extend(mirrored);
        columns.sort_by(|a, b| a.0.total_cmp(&b.0));
    }
    from_columns(Photometry::TypeB, vertical, &columns)
}

/// Type B's angles (V, H) of the direction whose Type C angles are (θ, φ), in the frame
/// of the module's text; V is 0 on the lateral axis, where it means nothing.
fn type_b_angles(theta: f32, phi: f32) -> (f32, f32) {
    let (x, y, z) = (
        theta.sin() * phi.cos(),
        theta.sin() * phi.sin(),
        theta.cos(),
    );
    (x.atan2(z), (-y).clamp(-1.0, 1.0).asin())
}

/// The φ range (radians) of column `column` of the stand-in grid.
fn bound_column(column: usize) -> (f32, f32) {
    (
        column as f32 / BOUND_COLUMNS as f32 * TAU,
        ((column + 1) as f32 / BOUND_COLUMNS as f32 * TAU).min(TAU - 1e-6),
    )
}

/// The box of Type B angles (V, H) that holds every direction of a cell of Type C
/// angles θ in [t0, t1], φ in [p0, p1] (p1 ≤ 2π), or None when the cell lies behind
/// the lamp, where Type B is dark. With x = sin θ cos φ, y = sin θ sin φ, z = cos θ:
/// H = −asin y is monotone in sin θ · sin φ and, in front of the lamp, V = atan(tan θ ·
/// cos φ); both products of a factor in θ (non-negative and rising over [0, π/2]) and
/// one in φ are extreme at the ends of the factors' ranges, and those of sin φ and cos φ
/// over [p0, p1] are at its ends or at the quarter turns inside it. Next to the lateral
/// axis (H = ±90°) V takes every value.
fn type_b_box(theta: (f32, f32), phi: (f32, f32)) -> Option<((f32, f32), (f32, f32))> {
    const EPS: f32 = 1e-5;
    let (t0, t1) = (theta.0, theta.1.min(FRAC_PI_2));
    if t0 > t1 + EPS {
        return None;
    }
    let (p0, p1) = phi;
    let range = |f: fn(f32) -> f32| -> (f32, f32) {
        let mut r = (f(p0).min(f(p1)), f(p0).max(f(p1)));
        for k in 0..=4 {
            let q = k as f32 * FRAC_PI_2;
            if q > p0 && q < p1 {
                r = (r.0.min(f(q)), r.1.max(f(q)));
            }
        }
        r
    };
    let (sin_lo, sin_hi) = range(f32::sin);
    let (cos_lo, cos_hi) = range(f32::cos);
    // H from sin θ · sin φ (sin θ ≥ 0).
    let products = |a: (f32, f32), b: (f32, f32)| -> (f32, f32) {
        let p = [a.0 * b.0, a.0 * b.1, a.1 * b.0, a.1 * b.1];
        (
            p.iter().copied().fold(f32::INFINITY, f32::min),
            p.iter().copied().fold(f32::NEG_INFINITY, f32::max),
        )
    };
    let (y_lo, y_hi) = products((t0.sin(), t1.sin()), (sin_lo, sin_hi));
    let h = (
        (-y_hi).clamp(-1.0, 1.0).asin() - EPS,
        (-y_lo).clamp(-1.0, 1.0).asin() + EPS,
    );
    // V from the corners (θ, cos φ): atan2(sin θ cos φ, cos θ) rises with tan θ · cos φ.
    let mut v = (f32::INFINITY, f32::NEG_INFINITY);
    for t in [t0, t1] {
        for c in [cos_lo, cos_hi] {
            let a = (t.sin() * c).atan2(t.cos());
            v = (v.0.min(a), v.1.max(a));
        }
    }
    let v = if h.0 <= -FRAC_PI_2 + 2.0 * EPS || h.1 >= FRAC_PI_2 - 2.0 * EPS {
        (-FRAC_PI_2 - EPS, FRAC_PI_2 + EPS)
    } else {
        (v.0 - EPS, v.1 + EPS)
    };
    Some((v, h))
}

impl IesProfile {
    /// Candela toward the direction of Type C angles (`theta`, `phi`) in the light's
    /// frame (radians; `phi` in [0, 2π)), whatever the profile's own type: interpolated
    /// bilinearly in the profile's angles; 0 outside them.
    pub fn eval(&self, theta: f32, phi: f32) -> f32 {
        match self.photometry {
            Photometry::TypeC => self.lookup(theta, phi),
            Photometry::TypeB => {
                let (v, h) = type_b_angles(theta, phi);
                self.lookup(v, h)
            }
        }
    }

    /// The table at the profile's own angles (vertical, horizontal), bilinear; 0 outside
    /// its vertical angles, and for Type B outside its horizontal ones too.
    pub fn lookup(&self, vertical: f32, horizontal: f32) -> f32 {
        let nv = self.vertical.len();
        let nh = self.horizontal.len();
        let outside =
            |angles: &[f32], x: f32| x < angles[0] - 1e-6 || x > angles[angles.len() - 1] + 1e-6;
        if outside(&self.vertical, vertical)
            || (self.photometry == Photometry::TypeB && outside(&self.horizontal, horizontal))
        {
            return 0.0;
        }
        let (iv, tv) = if nv == 1 {
            (0, 0.0)
        } else {
            bracket(&self.vertical, vertical)
        };
        let (ih, th) = if nh == 1 {
            (0, 0.0)
        } else {
            bracket(&self.horizontal, horizontal)
        };
        let at = |h: usize, v: usize| self.candela[h * nv + v];
        let column = |h: usize| {
            if nv == 1 {
                at(h, 0)
            } else {
                at(h, iv) * (1.0 - tv) + at(h, iv + 1) * tv
            }
        };
        if nh == 1 {
            column(0)
        } else {
            column(ih) * (1.0 - th) + column(ih + 1) * th
        }
    }

    /// ∫ I dω over the sphere (candela·sr, the lamp's flux in lumens), by the midpoint
    /// rule on a fine grid of the interpolated table.
    pub fn flux(&self) -> f64 {
        let (n_theta, n_phi) = (512usize, 256usize);
        let mut sum = 0.0f64;
        for i in 0..n_theta {
            let theta = (i as f64 + 0.5) / n_theta as f64 * std::f64::consts::PI;
            let ring = theta.sin() * (std::f64::consts::PI / n_theta as f64);
            let mut row = 0.0f64;
            for j in 0..n_phi {
                let phi = (j as f64 + 0.5) / n_phi as f64 * std::f64::consts::TAU;
                row += self.eval(theta as f32, phi as f32) as f64;
            }
            sum += ring * row * std::f64::consts::TAU / n_phi as f64;
        }
        sum
    }

    /// The Type C vertical angles θ (radians, from the aim) outside which the profile
    /// is dark, or None when it is dark everywhere. Type C: from the angle before its
    /// first lit one to the angle after its last (the interpolation reaches those).
    /// Type B: from the aim to the farthest corner of the lit angles (with their
    /// neighbours), cos θ = cos H cos V.
    pub fn lit_vertical_range(&self) -> Option<(f32, f32)> {
        let (nv, nh) = (self.vertical.len(), self.horizontal.len());
        let lit_v = |v: usize| (0..nh).any(|h| self.candela[h * nv + v] > 0.0);
        let first = (0..nv).find(|&v| lit_v(v))?;
        let last = (0..nv).rfind(|&v| lit_v(v))?;
        let (first, last) = (first.saturating_sub(1), (last + 1).min(nv - 1));
        match self.photometry {
            Photometry::TypeC => Some((self.vertical[first], self.vertical[last])),
            Photometry::TypeB => {
                let lit_h = |h: usize| (0..nv).any(|v| self.candela[h * nv + v] > 0.0);
                let h_first = (0..nh).find(|&h| lit_h(h))?.saturating_sub(1);
                let h_last = ((0..nh).rfind(|&h| lit_h(h))? + 1).min(nh - 1);
                let v_max = self.vertical[first].abs().max(self.vertical[last].abs());
                let h_max = self.horizontal[h_first]
                    .abs()
                    .max(self.horizontal[h_last].abs());
                let cos = (v_max.min(FRAC_PI_2).cos() * h_max.min(FRAC_PI_2).cos()).clamp(0.0, 1.0);
                Some((0.0, cos.acos()))
            }
        }
    }

    /// The largest candela value.
    pub fn peak(&self) -> f32 {
        self.candela.iter().fold(0.0, |m, &c| m.max(c))
    }

    /// The largest candela over each cell of a grid of [`BOUND_ROWS`] rows uniform in
    /// cos θ (from the light's direction, cos θ = 1, to its opposite) by
    /// [`BOUND_COLUMNS`] columns uniform in φ, row-major: RIS's candidates weigh this
    /// stand-in instead of looking the table up (`punctual_profile_bound`), and the kept
    /// one its exact value. It is never below the profile, so positive wherever the
    /// profile is: a Type C cell is a box of the table's angles, whose maximum
    /// [`IesProfile::box_max`] finds exactly; a Type B table's maximum is taken over the
    /// box of (V, H) that holds the cell (`type_b_box`).
    pub fn bounds(&self) -> Vec<f32> {
        let mut out = Vec::with_capacity(BOUND_ROWS * BOUND_COLUMNS);
        for row in 0..BOUND_ROWS {
            // Rows are uniform in cos θ, from 1 down to −1 (the kernel needs no acos).
            let (t0, t1) = (
                (1.0 - 2.0 * row as f32 / BOUND_ROWS as f32)
                    .clamp(-1.0, 1.0)
                    .acos(),
                (1.0 - 2.0 * (row + 1) as f32 / BOUND_ROWS as f32)
                    .clamp(-1.0, 1.0)
                    .acos(),
            );
            for column in 0..BOUND_COLUMNS {
                out.push(self.cell_max((t0, t1), bound_column(column)));
            }
        }
        out
    }

    /// The largest candela over the directions whose Type C angles lie in the cell
    /// `theta` × `phi` (radians, from the aim): exact for Type C, whose cell is a box of
    /// the table's angles; for Type B the maximum over a box of (V, H) that holds the
    /// cell (`type_b_box`), so never below the profile there.
    fn cell_max(&self, theta: (f32, f32), phi: (f32, f32)) -> f32 {
        match self.photometry {
            Photometry::TypeC => self.box_max(theta, phi),
            Photometry::TypeB => match type_b_box(theta, phi) {
                Some((v, h)) => self.box_max(v, h),
                None => 0.0,
            },
        }
    }

    /// The largest candela toward any direction between `t0` and `t1` (radians) from
    /// the aim, never below the profile there: the largest of the cells of
    /// [`BOUND_COLUMNS`] columns of φ across the band.
    pub fn band_max(&self, t0: f32, t1: f32) -> f32 {
        (0..BOUND_COLUMNS)
            .map(|column| self.cell_max((t0, t1), bound_column(column)))
            .fold(0.0, f32::max)
    }

    /// The largest value of the table over a box of its own angles: the bilinear table
    /// is largest at a corner of one of the pieces the box's edges and the file's
    /// angles cut it into, so at one of the products of those angles.
    fn box_max(&self, vertical: (f32, f32), horizontal: (f32, f32)) -> f32 {
        let cuts = |angles: &[f32], (lo, hi): (f32, f32)| -> Vec<f32> {
            let mut c = vec![lo, hi];
            c.extend(angles.iter().copied().filter(|&a| a > lo && a < hi));
            c
        };
        let mut m = 0.0f32;
        for &v in &cuts(&self.vertical, vertical) {
            for &h in &cuts(&self.horizontal, horizontal) {
                m = m.max(self.lookup(v, h));
            }
        }
        m
    }

    /// Appends the kernel's form (`inc/lights.glsl`, `punctual_profile`): the counts
    /// as bits, the angles, the table, then the stand-in grid of [`IesProfile::bounds`].
    pub fn pack(&self, out: &mut Vec<f32>) {
        out.push(f32::from_bits(self.vertical.len() as u32));
        let type_b = match self.photometry {
            Photometry::TypeC => 0,
            Photometry::TypeB => TYPE_B_BIT,
        };
        out.push(f32::from_bits(self.horizontal.len() as u32 | type_b));
        out.extend_from_slice(&self.vertical);
        out.extend_from_slice(&self.horizontal);
        out.extend_from_slice(&self.candela);
        out.extend(self.bounds());
    }
}

/// The profile packed at `offset` of a scene's profile array (the inverse of `pack`).
pub fn unpack(data: &[f32], offset: usize) -> IesProfile {
    let nv = data[offset].to_bits() as usize;
    let nh_bits = data[offset + 1].to_bits();
    let nh = (nh_bits & !TYPE_B_BIT) as usize;
    let v = offset + 2;
    let h = v + nv;
    let c = h + nh;
    IesProfile {
        photometry: if nh_bits & TYPE_B_BIT != 0 {
            Photometry::TypeB
        } else {
            Photometry::TypeC
        },
        vertical: data[v..h].to_vec(),
        horizontal: data[h..c].to_vec(),
        candela: data[c..c + nv * nh].to_vec(),
    }
}

/// The interval of `angles` holding `x` (clamped to the ends) and where in it x lies.
fn bracket(angles: &[f32], x: f32) -> (usize, f32) {
    let n = angles.len();
    let i = angles[1..n - 1].partition_point(|&a| a <= x);
    let (a, b) = (angles[i], angles[i + 1]);
    (i, ((x - a) / (b - a)).clamp(0.0, 1.0))
}

/// The profile a light of the extension's root list names: read from its URI or buffer
/// view. `read_uri` reads a URI as the loader reads buffers (its safety rules apply);
/// `view` gives a buffer view's bytes.
pub(super) fn load(
    entry: &serde_json::Value,
    index: usize,
    read_uri: &mut dyn FnMut(&str) -> Result<Vec<u8>, String>,
    view: &dyn Fn(usize) -> Option<Vec<u8>>,
) -> Result<(IesProfile, Vec<String>), String> {
    let what = match entry.get("name").and_then(|n| n.as_str()) {
        Some(name) => format!("{EXTENSION} light {index} (`{name}`)"),
        None => format!("{EXTENSION} light {index}"),
    };
    let bytes = match (entry.get("uri"), entry.get("bufferView")) {
        (Some(uri), None) => {
            let uri = uri
                .as_str()
                .ok_or_else(|| format!("{what}: `uri` is not a string"))?;
            read_uri(uri).map_err(|e| format!("{what}: cannot load `{uri}`: {e}"))?
        }
        (None, Some(v)) => {
            let mime = entry.get("mimeType").and_then(|m| m.as_str());
            if mime != Some(MIME_TYPE) {
                return Err(format!(
                    "{what}: a profile in a buffer view must have mimeType `{MIME_TYPE}`"
                ));
            }
            let v = v
                .as_u64()
                .ok_or_else(|| format!("{what}: `bufferView` is not an index"))?;
            view(v as usize).ok_or_else(|| format!("{what}: buffer view {v} does not exist"))?
        }
        _ => return Err(format!("{what}: needs either a `uri` or a `bufferView`")),
    };
    let (profile, warnings) = parse(&bytes).map_err(|e| format!("{what}: the profile {e}"))?;
    let warnings = warnings
        .into_iter()
        .map(|w| format!("{what}: {w}"))
        .collect();
    Ok((profile, warnings))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn file(header: &str, v: &[f64], h: &[f64], c: &[f64]) -> String {
        typed_file(1, header, v, h, c)
    }

    /// A profile of photometric type `kind` (1: C, 2: B, 3: A).
    fn typed_file(kind: u32, header: &str, v: &[f64], h: &[f64], c: &[f64]) -> String {
        let list = |x: &[f64]| {
            x.iter()
                .map(|a| a.to_string())
                .collect::<Vec<_>>()
                .join(" ")
        };
        format!(
            "IESNA:LM-63-2002\n[TEST] unit\n{header}\n1 1000 2 {} {} {kind} 2 0 0 0\n0.5 1 100\n{}\n{}\n{}\n",
            v.len(),
            h.len(),
            list(v),
            list(h),
            list(c)
        )
    }

    /// The file's own value at one of its angles, folded by its symmetry (written
    /// here again, apart from `unfold`).
    fn folded(h: &[f64], phi: f64) -> f64 {
        let last = h[h.len() - 1];
        let p = phi.rem_euclid(360.0);
        if h.len() == 1 {
            0.0
        } else if last == 90.0 {
            let q = p % 180.0;
            if q > 90.0 {
                180.0 - q
            } else {
                q
            }
        } else if h[0] == 90.0 {
            // Mirror across the 90–270° plane: φ ↦ 180° − φ.
            if (90.0..=270.0).contains(&p) {
                p
            } else {
                (540.0 - p) % 360.0
            }
        } else if last == 180.0 {
            if p > 180.0 {
                360.0 - p
            } else {
                p
            }
        } else {
            p
        }
    }

    #[test]
    fn every_symmetry_unfolds_to_the_files_values() {
        let v = [0.0, 30.0, 60.0, 90.0];
        let cases: Vec<Vec<f64>> = vec![
            vec![0.0],
            vec![0.0, 45.0, 90.0],
            vec![0.0, 60.0, 120.0, 180.0],
            vec![90.0, 150.0, 210.0, 270.0],
            vec![0.0, 90.0, 180.0, 270.0, 360.0],
            vec![0.0, 120.0, 240.0],
        ];
        for h in cases {
            // Distinct values per column and angle.
            let c: Vec<f64> = (0..h.len() * v.len())
                .map(|i| 10.0 + i as f64 * 3.0)
                .collect();
            let (p, _) = parse(file("TILT=NONE", &v, &h, &c).as_bytes()).unwrap();
            assert_eq!(p.horizontal.first().copied(), Some(0.0), "{h:?}");
            if h.len() > 1 {
                assert!((p.horizontal.last().unwrap() - std::f32::consts::TAU).abs() < 1e-5);
            }
            for phi in (0..72).map(|k| k as f64 * 5.0) {
                let f = folded(&h, phi);
                // The full profile that stops short of 360° wraps to its 0° column.
                let column = h.iter().position(|&a| (a - f).abs() < 1e-9);
                for (iv, &theta) in v.iter().enumerate() {
                    let got = p.eval((theta as f32).to_radians(), (phi as f32).to_radians());
                    if let Some(col) = column {
                        let want = c[col * v.len() + iv] * 2.0 * 0.5; // multiplier × ballast
                        assert!(
                            (got as f64 - want).abs() < 1e-3 * want,
                            "{h:?} φ={phi} θ={theta}: {got} vs {want}"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn interpolates_bilinearly_and_is_dark_outside_its_vertical_angles() {
        let v = [0.0, 90.0];
        let h = [0.0, 180.0];
        let c = [100.0, 50.0, 20.0, 10.0];
        let (p, _) = parse(file("TILT=NONE", &v, &h, &c).as_bytes()).unwrap();
        let deg = |a: f32| a.to_radians();
        // θ 45°, φ 90°: the mean of the four corners, times the factors (1).
        let got = p.eval(deg(45.0), deg(90.0));
        assert!((got - 45.0).abs() < 1e-3, "{got}");
        // Mirrored: φ 270° sees φ 90°.
        assert!((p.eval(deg(45.0), deg(270.0)) - 45.0).abs() < 1e-3);
        assert_eq!(p.eval(deg(100.0), 0.0), 0.0);
        // 90–270° files wrap across 0°: φ 0° mirrors 180°, halfway between 150° and 210°.
        let (p, _) = parse(
            file(
                "TILT=NONE",
                &[0.0],
                &[90.0, 150.0, 210.0, 270.0],
                &[1.0, 2.0, 4.0, 8.0],
            )
            .as_bytes(),
        )
        .unwrap();
        assert!(
            (p.eval(0.0, 0.0) - 3.0).abs() < 1e-4,
            "{}",
            p.eval(0.0, 0.0)
        );
        assert!((p.eval(0.0, deg(30.0)) - 2.0).abs() < 1e-4);
        assert!((p.eval(0.0, deg(330.0)) - 4.0).abs() < 1e-4);
        // A lamp of 100 cd over the lower hemisphere only: flux ≈ 2π·(linear in θ).
        let round = parse(file("TILT=NONE", &[0.0, 90.0], &[0.0], &[100.0, 100.0]).as_bytes())
            .unwrap()
            .0;
        let f = round.flux();
        assert!(
            (f - 2.0 * std::f64::consts::PI * 100.0).abs() < 0.01 * f,
            "{f}"
        );
    }

    /// The stand-in grid holds the profile from above in every cell, so it is positive
    /// wherever the profile is; and it is not loose: a 41 × 41 sampling of each cell
    /// comes within 10 % of it (Type C, whose cells are boxes of its angles). A Type B
    /// table is bounded over the box of its angles that holds a cell: never below it
    /// either, and on these tables of unrelated neighbouring values within 80 % of the
    /// sampled maximum on average over the lit cells (a box holds more than its cell).
    #[test]
    fn bounds_hold_the_profile_in_every_cell() {
        let values = |n: usize| -> Vec<f64> {
            (0..n)
                .map(|i| {
                    if i % 7 == 6 {
                        0.0
                    } else {
                        ((i * 37) % 11) as f64
                    }
                })
                .collect()
        };
        let v: Vec<f64> = vec![0.0, 7.0, 20.0, 33.0, 61.0, 90.0, 100.0];
        let h: Vec<f64> = vec![0.0, 10.0, 45.0, 80.0, 90.0];
        let c = values(v.len() * h.len());
        let (p, _) = parse(file("TILT=NONE", &v, &h, &c).as_bytes()).unwrap();
        check_bounds(&p, 0.9);
        let v: Vec<f64> = vec![-90.0, -40.0, -5.0, 0.0, 12.0, 50.0, 90.0];
        for h in [
            vec![0.0, 10.0, 45.0, 80.0, 90.0],
            vec![-70.0, -20.0, 0.0, 35.0, 60.0],
        ] {
            let c = values(v.len() * h.len());
            let (p, _) = parse(typed_file(2, "TILT=NONE", &v, &h, &c).as_bytes()).unwrap();
            // 0.88 on both tables (2026-12-07).
            let mean = check_bounds(&p, 0.0);
            assert!(mean >= 0.8, "type B {h:?}: mean tightness {mean}");
        }
    }

    /// Asserts the bound holds in every cell and comes within `tightness` of the
    /// sampled maximum in each (0: not asked); returns the mean ratio over lit cells.
    fn check_bounds(p: &IesProfile, tightness: f32) -> f32 {
        let bounds = p.bounds();
        let mut ratios = Vec::new();
        let (rows, columns) = (BOUND_ROWS, BOUND_COLUMNS);
        for row in 0..rows {
            for column in 0..columns {
                let bound = bounds[row * columns + column];
                let mut reached = 0.0f32;
                for i in 0..=40 {
                    for j in 0..=40 {
                        let cos = 1.0 - 2.0 * (row as f32 + i as f32 / 40.0) / rows as f32;
                        let theta = cos.clamp(-1.0, 1.0).acos();
                        let phi = ((column as f32 + j as f32 / 40.0) / columns as f32
                            * std::f32::consts::TAU)
                            .min(std::f32::consts::TAU - 1e-6);
                        let value = p.eval(theta, phi);
                        assert!(
                            value <= bound * (1.0 + 1e-5) + 1e-6,
                            "{:?} cell ({row}, {column}): {value} > {bound}",
                            p.photometry
                        );
                        reached = reached.max(value);
                    }
                }
                // Within the sampling's resolution of the file's angles.
                assert!(
                    reached >= tightness * bound,
                    "{:?} cell ({row}, {column}): {reached} < {bound}",
                    p.photometry
                );
                if bound > 0.0 {
                    ratios.push(reached / bound);
                }
            }
        }
        ratios.iter().sum::<f32>() / ratios.len() as f32
    }

    /// Type B's frame, from the extension's text: (0°, 0°) along −Z, V tilting toward
    /// +X, H turning clockwise seen from +X (toward −Y); a 0–90° file mirrored across the
    /// vertical plane; dark behind the lamp and beyond the file's angles; packed and
    /// unpacked with its type.
    #[test]
    fn type_b_profiles_lie_in_their_frame() {
        let v = [-60.0, -20.0, 0.0, 30.0, 90.0];
        let deg = |a: f64| (a as f32).to_radians();
        // The direction of Type B angles (V, H), then its Type C angles (θ, φ).
        let c_angles = |v: f64, h: f64| -> (f32, f32) {
            let (v, h) = (v.to_radians(), h.to_radians());
            let d = [h.cos() * v.sin(), -h.sin(), -h.cos() * v.cos()];
            (
                (-d[2]).clamp(-1.0, 1.0).acos() as f32,
                d[1].atan2(d[0]).rem_euclid(std::f64::consts::TAU) as f32,
            )
        };
        for h in [
            vec![0.0, 25.0, 60.0, 90.0],
            vec![-80.0, -30.0, 0.0, 45.0, 70.0],
        ] {
            let c: Vec<f64> = (0..v.len() * h.len()).map(|i| 1.0 + i as f64).collect();
            let (p, _) = parse(typed_file(2, "TILT=NONE", &v, &h, &c).as_bytes()).unwrap();
            assert_eq!(p.photometry, Photometry::TypeB);
            let mirrored = h[0] == 0.0;
            for (ih, &ha) in h.iter().enumerate() {
                for (iv, &va) in v.iter().enumerate() {
                    let want = c[ih * v.len() + iv] as f32; // multiplier × ballast = 1
                    let sides: &[f64] = if mirrored { &[1.0, -1.0] } else { &[1.0] };
                    for &side in sides {
                        // Off the lateral axis, where V is moot.
                        if ha.abs() == 90.0 {
                            continue;
                        }
                        let (theta, phi) = c_angles(va, side * ha);
                        let got = p.eval(theta, phi);
                        assert!(
                            (got - want).abs() < 1e-3 * want,
                            "{h:?} V={va} H={}: {got} vs {want}",
                            side * ha
                        );
                    }
                }
            }
            // Bilinear between the file's angles, in (V, H).
            let (va, ha) = (15.0, if mirrored { 40.0 } else { 20.0 });
            let (iv, ih) = (3, if mirrored { 1 } else { 2 });
            let (tv, th) = (
                (va - v[iv - 1]) / (v[iv] - v[iv - 1]),
                (ha - h[ih]) / (h[ih + 1] - h[ih]),
            );
            let at = |i: usize, j: usize| c[i * v.len() + j];
            let want = (1.0 - th) * ((1.0 - tv) * at(ih, iv - 1) + tv * at(ih, iv))
                + th * ((1.0 - tv) * at(ih + 1, iv - 1) + tv * at(ih + 1, iv));
            let (theta, phi) = c_angles(va, ha);
            assert!((p.eval(theta, phi) as f64 - want).abs() < 1e-3 * want);
            // Dark behind the lamp, below its first vertical angle and (the full file)
            // beyond its horizontal angles.
            assert_eq!(p.eval(deg(120.0), deg(10.0)), 0.0);
            let (theta, phi) = c_angles(-70.0, 10.0);
            assert_eq!(p.eval(theta, phi), 0.0);
            if !mirrored {
                let (theta, phi) = c_angles(10.0, 75.0);
                assert_eq!(p.eval(theta, phi), 0.0);
                let (theta, phi) = c_angles(10.0, -75.0);
                assert!(p.eval(theta, phi) > 0.0);
            }
            // Its lit cone holds every lit direction.
            let (lo, hi) = p.lit_vertical_range().unwrap();
            for i in 0..200 {
                for j in 0..200 {
                    let (theta, phi) = (
                        i as f32 / 199.0 * std::f32::consts::PI,
                        j as f32 / 200.0 * std::f32::consts::TAU,
                    );
                    if p.eval(theta, phi) > 0.0 {
                        assert!(
                            theta >= lo - 1e-5 && theta <= hi + 1e-5,
                            "θ {theta} outside {lo}–{hi}"
                        );
                    }
                }
            }
            let mut packed = vec![7.0];
            p.pack(&mut packed);
            assert_eq!(unpack(&packed, 1), p);
        }
        // The explicit frame: V = 30° leans toward +X, H = 30° toward −Y.
        let c: Vec<f64> = vec![0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 8.0, 0.0];
        let (p, _) = parse(
            typed_file(
                2,
                "TILT=NONE",
                &[-90.0, 0.0, 30.0, 90.0],
                &[-90.0, 30.0],
                &c,
            )
            .as_bytes(),
        )
        .unwrap();
        // Its one lit value, at V = 30° and H = 30°, lies along (cos 30° sin 30°,
        // −sin 30°, −cos 30° cos 30°).
        let d = glam::Vec3::new(0.75f32.sqrt() * 0.5, -0.5, -0.75);
        let (theta, phi) = (
            (-d.z).acos(),
            d.y.atan2(d.x).rem_euclid(std::f32::consts::TAU),
        );
        assert!(
            (p.eval(theta, phi) - 8.0).abs() < 1e-3,
            "{}",
            p.eval(theta, phi)
        );
    }

    #[test]
    fn tilt_data_is_skipped_and_said() {
        let text = file(
            "TILT=INCLUDE\n1\n3\n0 45 90\n1 0.9 0.8",
            &[0.0, 90.0],
            &[0.0],
            &[5.0, 6.0],
        );
        let (p, warnings) = parse(text.as_bytes()).unwrap();
        assert_eq!(p.candela, vec![5.0, 6.0]);
        assert_eq!(warnings.len(), 1);
    }

    /// Every prefix of a profile (Type C and Type B), and the profile with any byte
    /// changed to any of the characters its syntax uses, is read or
    /// refused: never a panic, never a non-finite or negative value.
    #[test]
    fn damaged_profiles_are_errors_never_panics() {
        let v = [0.0, 22.5, 45.0, 67.5, 90.0];
        let h = [0.0, 45.0, 90.0];
        let c: Vec<f64> = (0..15).map(|i| 1.0 + i as f64).collect();
        let check = |bytes: &[u8]| {
            if let Ok((p, _)) = parse(bytes) {
                assert!(p.candela.iter().all(|c| c.is_finite() && *c >= 0.0));
                assert_eq!(p.candela.len(), p.vertical.len() * p.horizontal.len());
                let _ = p.eval(0.3, 1.0);
                let _ = p.flux();
                assert!(p.bounds().iter().all(|b| b.is_finite() && *b >= 0.0));
                let _ = p.lit_vertical_range();
            }
        };
        let tilt = "TILT=INCLUDE\n1\n2\n0 90\n1 1";
        let v_b = [-90.0, -30.0, 0.0, 45.0, 90.0];
        for text in [
            file(tilt, &v, &h, &c).into_bytes(),
            typed_file(2, tilt, &v_b, &h, &c).into_bytes(),
        ] {
            for n in 0..text.len() {
                check(&text[..n]);
            }
            let alphabet = b"0123456789-.e ,\nTILT=NOE";
            for i in 0..text.len() {
                for &b in alphabet {
                    let mut bytes = text.clone();
                    bytes[i] = b;
                    check(&bytes);
                }
            }
        }
    }

    #[test]
    fn malformed_profiles_are_errors_that_say_why() {
        let ok = |h: &str| file(h, &[0.0, 90.0], &[0.0], &[1.0, 2.0]);
        let cases = [
            ("no tilt", "IESNA:LM-63-2002\n1 2 3".to_string(), "TILT"),
            (
                "cut short",
                ok("TILT=NONE")[..60].to_string(),
                "ends before",
            ),
            (
                "type A",
                ok("TILT=NONE").replace("1 2 0 0 0", "3 2 0 0 0"),
                "Type A",
            ),
            (
                "type B behind",
                typed_file(2, "TILT=NONE", &[0.0, 120.0], &[0.0, 90.0], &[1.0; 4]),
                "outside Type B's",
            ),
            (
                "type B one angle",
                typed_file(2, "TILT=NONE", &[0.0, 90.0], &[0.0], &[1.0; 2]),
                "two of each",
            ),
            (
                "word",
                ok("TILT=NONE").replace("100\n", "watts\n"),
                "not a number",
            ),
            (
                "negative",
                file("TILT=NONE", &[0.0, 90.0], &[0.0], &[1.0, -2.0]),
                "negative",
            ),
            (
                "order",
                file("TILT=NONE", &[90.0, 0.0], &[0.0], &[1.0, 2.0]),
                "do not increase",
            ),
            (
                "range",
                file("TILT=NONE", &[0.0, 45.0], &[10.0, 50.0], &[1.0; 4]),
                "horizontal angles",
            ),
            (
                "huge",
                ok("TILT=NONE").replace("1000 2 2 1", "1000 2 99999999 1"),
                "count",
            ),
            (
                "nan",
                file("TILT=NONE", &[0.0, 90.0], &[0.0], &[1.0, f64::NAN]),
                "finite",
            ),
        ];
        for (name, text, needle) in cases {
            let e = parse(text.as_bytes()).unwrap_err();
            assert!(e.contains(needle), "{name}: {e}");
        }
    }
}
