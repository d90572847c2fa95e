//! Cameras: glTF perspective and orthographic cameras, chosen by name or index, or a
//! look-at view given on the command line.

use glam::{Mat4, Vec3};

/// A projection, glTF conventions (the camera looks down −Z with +Y up).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Projection {
    /// Vertical field of view in radians; aspect ratio width/height if the file fixes it.
    Perspective { yfov: f32, aspect: Option<f32> },
    /// Half extents of the view volume.
    Orthographic { xmag: f32, ymag: f32 },
}

/// The planes that bound what camera rays see, at distances along the view axis (glTF's
/// `znear` and `zfar`): the ray through view direction d (unit, camera space) starts at
/// near / −d.z and ends at far / −d.z, as a rasteriser's clip planes and Mitsuba's
/// `near_clip`/`far_clip` cut the view. Only camera rays are clipped.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClipPlanes {
    pub near: f32,
    /// `f32::INFINITY`: no far plane (glTF's infinite projection).
    pub far: f32,
}

impl ClipPlanes {
    /// Everything in front of the camera.
    pub const NONE: ClipPlanes = ClipPlanes {
        near: 0.0,
        far: f32::INFINITY,
    };

    pub fn is_none(&self) -> bool {
        *self == Self::NONE
    }
}

/// A camera placed in the world.
#[derive(Clone, Debug)]
pub struct Camera {
    pub name: String,
    pub to_world: Mat4,
    pub projection: Projection,
    /// The file's clip planes (`ClipPlanes::NONE` for a look-at view, or when the command
    /// line asks to ignore them).
    pub clip: ClipPlanes,
}

/// A view given on the command line, replacing or completing the file's camera.
#[derive(Clone, Debug, Default)]
pub struct CameraOverride {
    /// Eye and target positions.
    pub look_at: Option<(Vec3, Vec3)>,
    /// Up vector for `look_at` (default +Y).
    pub up: Option<Vec3>,
    /// Vertical field of view in degrees.
    pub fov_degrees: Option<f32>,
    /// See everything in front of the camera, whatever the file's clip planes
    /// (`--no-clip-planes`).
    pub no_clip_planes: bool,
}

impl Camera {
    /// A perspective camera at `eye` looking at `target`.
    pub fn look_at(eye: Vec3, target: Vec3, up: Vec3, yfov: f32) -> Camera {
        let forward = (target - eye).normalize_or(Vec3::NEG_Z);
        let up = if forward.cross(up).length_squared() < 1e-8 {
            if forward.y.abs() < 0.9 {
                Vec3::Y
            } else {
                Vec3::Z
            }
        } else {
            up
        };
        // look_at_rh builds world→view; the camera-to-world matrix is its inverse.
        let to_world = Mat4::look_at_rh(eye, eye + forward, up).inverse();
        Camera {
            name: "look-at".into(),
            to_world,
            projection: Projection::Perspective { yfov, aspect: None },
            clip: ClipPlanes::NONE,
        }
    }

    /// Apply a command-line override.
    pub fn with_override(mut self, o: &CameraOverride) -> Camera {
        if let Some((eye, target)) = o.look_at {
            let yfov = match self.projection {
                Projection::Perspective { yfov, .. } => yfov,
                Projection::Orthographic { .. } => 45f32.to_radians(),
            };
            self = Camera::look_at(eye, target, o.up.unwrap_or(Vec3::Y), yfov);
        }
        if let Some(fov) = o.fov_degrees {
            let aspect = match self.projection {
                Projection::Perspective { aspect, .. } => aspect,
                _ => None,
            };
            self.projection = Projection::Perspective {
                yfov: fov.to_radians(),
                aspect,
            };
        }
        if o.no_clip_planes {
            self.clip = ClipPlanes::NONE;
        }
        self
    }

    /// Aspect ratio fixed by the file, if any.
    pub fn aspect(&self) -> Option<f32> {
        match self.projection {
            Projection::Perspective { aspect, .. } => aspect,
            Projection::Orthographic { xmag, ymag } => (ymag > 0.0).then(|| xmag / ymag),
        }
    }

    pub fn position(&self) -> Vec3 {
        self.to_world.transform_point3(Vec3::ZERO)
    }

    /// The camera's rotation and translation only (glTF says camera nodes must not be
    /// scaled; a scaled one would distort rays, so the scale is removed).
    pub fn rigid_to_world(&self) -> Mat4 {
        let (_, rotation, translation) = self.to_world.to_scale_rotation_translation();
        Mat4::from_rotation_translation(rotation, translation)
    }
}
