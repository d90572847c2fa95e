//! `EXT_lights_ies`: point lights whose intensity varies with direction as an IES LM-63
//! photometric profile says (the data sheets luminaire makers publish). The extension's
//! text fixes the frame: the profile's (0°, 0°) point, where a Type C luminaire aims,
//! is the node's −Z; the X/Z plane is the vertical plane of horizontal angle 0, and
//! horizontal angles turn counter-clockwise about +Z, from +X toward +Y. A direction of
//! vertical angle θ and horizontal angle φ is (sin θ cos φ, sin θ sin φ, −cos θ).
//!
//! The file's candela table is interpolated bilinearly in (θ, φ) between its angles, as
//! lighting tools do. Its horizontal symmetry (one angle: round; 0–90°: each quadrant
//! alike; 0–180° or 90–270°: mirrored across a plane) is unfolded here into a table
//! over 0–360°, so the kernel (`inc/lights.glsl`, `punctual_profile`) looks up one
//! table whatever the file's symmetry. Outside the measured vertical angles the light
//! is dark (a 0–90° profile lights only the half-space it faces).

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

/// A Type C profile with its horizontal angles unfolded over 0–360°.
#[derive(Clone, Debug, PartialEq)]
pub struct IesProfile {
    /// Vertical angles θ in radians, increasing, within [0, π].
    pub vertical: Vec<f32>,
    /// Horizontal angles φ in radians, increasing from 0 to 2π; one entry for a round
    /// profile.
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
/// ignored (`TILT` data, which the extension does not ask for). Type C photometry only.
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
    match photometric_type as i64 {
        1 => {}
        2 | 3 => {
            return Err(format!(
                "uses Type {} photometry; lanterna reads Type C (1) only",
                if photometric_type as i64 == 2 {
                    "B (2)"
                } else {
                    "A (3)"
                }
            ))
        }
        _ => {
            return Err(format!(
                "has photometric type {photometric_type}, not 1, 2 or 3"
            ))
        }
    }
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
    if vertical[0] < 0.0 || vertical[nv - 1] > 180.0 {
        return Err(format!(
            "has vertical angles {}°–{}°, outside Type C's 0°–180°",
            vertical[0],
            vertical[nv - 1]
        ));
    }
    let symmetry = symmetry(&horizontal)?;
    let profile = unfold(&vertical, &horizontal, &candela, symmetry);
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
    IesProfile {
        vertical: vertical.iter().map(|a| a.to_radians() as f32).collect(),
        horizontal: columns.iter().map(|c| c.0.to_radians() as f32).collect(),
        candela: columns
            .iter()
            .flat_map(|c| c.1.iter().map(|&x| x as f32))
            .collect(),
    }
}

impl IesProfile {
    /// Candela toward vertical angle `theta` and horizontal angle `phi` (radians;
    /// `phi` in [0, 2π)), interpolated bilinearly; 0 outside the vertical angles.
    pub fn eval(&self, theta: f32, phi: f32) -> f32 {
        let nv = self.vertical.len();
        let (v0, v1) = (self.vertical[0], self.vertical[nv - 1]);
        if theta < v0 - 1e-6 || theta > v1 + 1e-6 {
            return 0.0;
        }
        let (iv, tv) = if nv == 1 {
            (0, 0.0)
        } else {
            bracket(&self.vertical, theta)
        };
        let (ih, th) = if self.horizontal.len() == 1 {
            (0, 0.0)
        } else {
            bracket(&self.horizontal, phi)
        };
        let at = |h: usize, v: usize| self.candela[h * nv + v];
        let column = |h: usize| {
            if nv == 1 {
                at(h, 0)
            } else {
                at(h, iv) * (1.0 - tv) + at(h, iv + 1) * tv
            }
        };
        if self.horizontal.len() == 1 {
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

    /// The vertical angles (radians) outside which the profile is dark: from the
    /// angle before its first lit one to the angle after its last (the interpolation
    /// reaches those), or None when it is dark everywhere.
    pub fn lit_vertical_range(&self) -> Option<(f32, f32)> {
        let nv = self.vertical.len();
        let lit = |v: usize| (0..self.horizontal.len()).any(|h| self.candela[h * nv + v] > 0.0);
        let first = (0..nv).find(|&v| lit(v))?;
        let last = (0..nv).rfind(|&v| lit(v))?;
        Some((
            self.vertical[first.saturating_sub(1)],
            self.vertical[(last + 1).min(nv - 1)],
        ))
    }

    /// The largest candela value.
    pub fn peak(&self) -> f32 {
        self.candela.iter().fold(0.0, |m, &c| m.max(c))
    }

    /// The largest candela over each cell of a grid of [`BOUND_ROWS`] rows uniform in
    /// cos θ (from the light's direction, cos θ = 1, to its opposite) by
    /// [`BOUND_COLUMNS`] columns uniform in φ, row-major: RIS's candidates weigh this
    /// stand-in instead of looking the table up (`punctual_profile_bound`), and the kept
    /// one its exact value. It is exact, so positive wherever the profile is: over a
    /// cell the bilinear table is largest at a corner of one of the pieces the cell's
    /// edges and the file's angles cut it into, so the maximum over the products of the
    /// cell's edge angles and the file's angles inside it.
    pub fn bounds(&self) -> Vec<f32> {
        let mut out = Vec::with_capacity(BOUND_ROWS * BOUND_COLUMNS);
        let cuts = |angles: &[f32], lo: f32, hi: f32| -> Vec<f32> {
            let mut c = vec![lo, hi];
            c.extend(angles.iter().copied().filter(|&a| a > lo && a < hi));
            c
        };
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
            let thetas = cuts(&self.vertical, t0, t1);
            for column in 0..BOUND_COLUMNS {
                let (p0, p1) = (
                    column as f32 / BOUND_COLUMNS as f32 * std::f32::consts::TAU,
                    (column + 1) as f32 / BOUND_COLUMNS as f32 * std::f32::consts::TAU,
                );
                let phis = cuts(&self.horizontal, p0, p1.min(std::f32::consts::TAU - 1e-6));
                let mut m = 0.0f32;
                for &t in &thetas {
                    for &p in &phis {
                        m = m.max(self.eval(t, p));
                    }
                }
                out.push(m);
            }
        }
        out
    }

    /// Appends the kernel's form (`inc/lights.glsl`, `punctual_profile`): the counts
    /// as bits, the angles, the table, then the stand-in grid of [`IesProfile::bounds`].
    pub fn pack(&self, out: &mut Vec<f32>) {
        out.push(f32::from_bits(self.vertical.len() as u32));
        out.push(f32::from_bits(self.horizontal.len() as u32));
        out.extend_from_slice(&self.vertical);
        out.extend_from_slice(&self.horizontal);
        out.extend_from_slice(&self.candela);
        out.extend(self.bounds());
    }
}

/// The profile packed at `offset` of a scene's profile array (the inverse of `pack`).
pub fn unpack(data: &[f32], offset: usize) -> IesProfile {
    let nv = data[offset].to_bits() as usize;
    let nh = data[offset + 1].to_bits() as usize;
    let v = offset + 2;
    let h = v + nv;
    let c = h + nh;
    IesProfile {
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
        let list = |x: &[f64]| {
            x.iter()
                .map(|a| a.to_string())
                .collect::<Vec<_>>()
                .join(" ")
        };
        format!(
            "IESNA:LM-63-2002\n[TEST] unit\n{header}\n1 1000 2 {} {} 1 2 0 0 0\n0.5 1 100\n{}\n{}\n{}\n",
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
    /// comes within 10 % of it.
    #[test]
    fn bounds_hold_the_profile_in_every_cell() {
        let v: Vec<f64> = vec![0.0, 7.0, 20.0, 33.0, 61.0, 90.0, 100.0];
        let h: Vec<f64> = vec![0.0, 10.0, 45.0, 80.0, 90.0];
        let c: Vec<f64> = (0..v.len() * h.len())
            .map(|i| {
                if i % 7 == 6 {
                    0.0
                } else {
                    ((i * 37) % 11) as f64
                }
            })
            .collect();
        let (p, _) = parse(file("TILT=NONE", &v, &h, &c).as_bytes()).unwrap();
        let bounds = p.bounds();
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
                            "cell ({row}, {column}): {value} > {bound}"
                        );
                        reached = reached.max(value);
                    }
                }
                // Within the sampling's resolution of the file's angles.
                assert!(
                    reached >= 0.9 * bound,
                    "cell ({row}, {column}): {reached} < {bound}"
                );
            }
        }
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

    /// Every prefix of a profile, and the profile with any byte changed to any of the
    /// characters its syntax uses, is read or
    /// refused: never a panic, never a non-finite or negative value.
    #[test]
    fn damaged_profiles_are_errors_never_panics() {
        let v = [0.0, 22.5, 45.0, 67.5, 90.0];
        let h = [0.0, 45.0, 90.0];
        let c: Vec<f64> = (0..15).map(|i| 1.0 + i as f64).collect();
        let text = file("TILT=INCLUDE\n1\n2\n0 90\n1 1", &v, &h, &c).into_bytes();
        let check = |bytes: &[u8]| {
            if let Ok((p, _)) = parse(bytes) {
                assert!(p.candela.iter().all(|c| c.is_finite() && *c >= 0.0));
                assert_eq!(p.candela.len(), p.vertical.len() * p.horizontal.len());
                let _ = p.eval(0.3, 1.0);
                let _ = p.flux();
            }
        };
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
                "type B",
                ok("TILT=NONE").replace("1 2 0 0 0", "2 2 0 0 0"),
                "Type B",
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
