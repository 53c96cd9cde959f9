//! The description of one synthetic scene, as stored in `scene.json`: enough
//! to render the frame again (with [`crate::Tracer::new`]).

use nalgebra::{Isometry3, Matrix3, Matrix4, Rotation3, Translation3, UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};

use crate::texture::TextureSpec;

/// Which generator made a scene.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SceneKind {
    /// OmniThings-like: random objects all around the rig, in a room or
    /// under a sky.
    Things,
    /// OmniHouse-like: furnished rooms with doorways, the rig inside.
    House,
    /// Built by hand (tests, user code).
    Custom,
}

impl SceneKind {
    pub fn name(self) -> &'static str {
        match self {
            Self::Things => "things",
            Self::House => "house",
            Self::Custom => "custom",
        }
    }
}

impl std::str::FromStr for SceneKind {
    type Err = crate::SynthError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "things" => Ok(Self::Things),
            "house" => Ok(Self::House),
            _ => Err(crate::SynthError::invalid(
                "scene kind",
                format!("unknown kind {s:?}, expected \"things\" or \"house\""),
            )),
        }
    }
}

/// Where an object sits: `X_parent = R(rotation) * diag(scale) * X_object + translation`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Placement {
    /// Rotation vector (axis times angle, radians), object to parent.
    pub rotation: [f64; 3],
    /// Metres.
    pub translation_m: [f64; 3],
    /// Scale along the object's own axes (metres per unit).
    pub scale: [f64; 3],
}

impl Placement {
    pub fn new(
        rotation: &UnitQuaternion<f64>,
        translation_m: Vector3<f64>,
        scale: [f64; 3],
    ) -> Self {
        Self {
            rotation: rotation.scaled_axis().into(),
            translation_m: translation_m.into(),
            scale,
        }
    }

    /// A translation and uniform scale, no rotation.
    pub fn at(translation_m: [f64; 3], scale: [f64; 3]) -> Self {
        Self {
            rotation: [0.0; 3],
            translation_m,
            scale,
        }
    }

    pub fn identity() -> Self {
        Self::at([0.0; 3], [1.0; 3])
    }

    pub fn rotation_matrix(&self) -> Matrix3<f64> {
        *Rotation3::new(Vector3::from(self.rotation)).matrix()
    }

    /// The rigid part (rotation + translation), without the scale.
    pub fn isometry(&self) -> Isometry3<f64> {
        Isometry3::from_parts(
            Translation3::from(Vector3::from(self.translation_m)),
            UnitQuaternion::from_scaled_axis(Vector3::from(self.rotation)),
        )
    }

    /// `parent_from_object` as a 4x4 affine matrix (scale included).
    pub fn matrix(&self) -> Matrix4<f64> {
        let linear = self.rotation_matrix() * Matrix3::from_diagonal(&Vector3::from(self.scale));
        let mut m = Matrix4::identity();
        m.fixed_view_mut::<3, 3>(0, 0).copy_from(&linear);
        m.fixed_view_mut::<3, 1>(0, 3)
            .copy_from(&Vector3::from(self.translation_m));
        m
    }
}

/// The geometry of an object, in its unit space (inside `[-1, 1]^3`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum ShapeSpec {
    /// The unit sphere (an ellipsoid when scaled unevenly), traced exactly.
    Sphere,
    /// The cube `[-1, 1]^3` (six exact rectangles). Seen from inside, a room.
    Box,
    Cylinder {
        segments: u32,
    },
    Cone {
        segments: u32,
    },
    Torus {
        minor: f32,
        major_segments: u32,
        minor_segments: u32,
    },
    /// A noise-displaced sphere.
    Blob {
        seed: i32,
        amplitude: f32,
        frequency: f32,
        subdivisions: u32,
    },
    /// A twisted, tapered prism of a random star-shaped polygon.
    Extrusion {
        seed: u64,
        corners: u32,
        layers: u32,
        twist: f32,
        taper: f32,
    },
    /// Mesh `index` of [`SceneSpec::meshes`].
    UserMesh {
        index: usize,
    },
    /// One rectangle: `[-1, 1]^2` in the object's xz plane (a floor, a wall).
    Rect,
    /// A thick-walled open pipe around y, inner radius `inner` (outer 1).
    Tube {
        segments: u32,
        inner: f32,
    },
    /// A flat frame in the xz plane around `cells_x x cells_z` square holes:
    /// bars of width `bar`, thickness `2 * half_y` (unit-space units).
    Grid {
        cells_x: u32,
        cells_z: u32,
        bar: f32,
        half_y: f32,
    },
    /// Bars of width `bar` along x, y and z through a `cells^3` grid.
    Lattice {
        cells: u32,
        bar: f32,
    },
}

/// One object of a scene.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ObjectSpec {
    pub shape: ShapeSpec,
    /// Object to scene ("world") frame.
    pub placement: Placement,
    pub texture: TextureSpec,
    /// Metres of the scene per texture-space unit. Texture space is the
    /// object's rotated and translated frame (not stretched by its scale).
    pub texture_scale_m: f64,
}

/// A sky at infinite depth (inverse depth 0); its brightness depends only on
/// the direction (world frame, y down), so every camera sees the same sky.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SkySpec {
    pub zenith: f32,
    pub horizon: f32,
    pub ground: f32,
    /// Fraction of the sky under clouds, `[0, 1]`.
    pub cloud_cover: f32,
    pub cloud_brightness: f32,
    pub cloud_freq: f32,
    pub cloud_seed: i32,
    /// Unit direction towards the sun, world frame.
    pub sun_dir: [f32; 3],
    pub sun_strength: f32,
}

/// Lambertian lighting: `reflectance * (ambient + diffuse * max(0, n.l))`.
/// View-independent, so that all cameras see the same surface brightness.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LightSpec {
    /// A point light at this position (world frame, metres), or, when
    /// `directional`, a light from this direction (unit vector towards it).
    pub position_m: [f64; 3],
    pub directional: bool,
    pub ambient: f32,
    pub diffuse: f32,
    /// A point light's falloff distance, metres: its diffuse term is scaled
    /// by `1 / (1 + (distance / range_m)^2)`. `None`: no falloff (and a
    /// directional light never falls off).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub range_m: Option<f64>,
}

/// Everything needed to render one frame.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SceneSpec {
    /// Generator name and version that made the scene.
    pub generator: String,
    pub kind: SceneKind,
    pub seed: u64,
    pub frame: u32,
    /// The rig's pose in the scene: `X_world = world_from_rig * X_rig`
    /// (scale ignored).
    pub world_from_rig: Placement,
    pub objects: Vec<ObjectSpec>,
    /// `None`: nothing beyond the geometry (black, inverse depth 0).
    pub sky: Option<SkySpec>,
    pub light: LightSpec,
    /// User mesh files referenced by [`ShapeSpec::UserMesh`].
    pub meshes: Vec<String>,
    /// More lights, added to [`Self::light`] (their `ambient` too).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub extra_lights: Vec<LightSpec>,
    /// Real-camera effects applied to the rendered 8-bit images, one per
    /// camera in rig order (`hard` datasets); empty: ideal cameras. The
    /// [`crate::Tracer`] renders the ideal images;
    /// [`crate::camera_effects::apply_all`] turns them into the dataset's.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub camera_effects: Vec<crate::camera_effects::CameraEffects>,
}

/// Name and version written into every scene.
pub fn generator_name() -> String {
    format!("omnimvs-synth {}", env!("CARGO_PKG_VERSION"))
}

impl SceneSpec {
    /// An empty custom scene, rig at the world origin, point light above.
    pub fn empty() -> Self {
        Self {
            generator: generator_name(),
            kind: SceneKind::Custom,
            seed: 0,
            frame: 0,
            world_from_rig: Placement::identity(),
            objects: Vec::new(),
            sky: None,
            light: LightSpec {
                position_m: [0.5, -3.0, 0.3],
                directional: false,
                ambient: 0.35,
                diffuse: 0.65,
                range_m: None,
            },
            meshes: Vec::new(),
            extra_lights: Vec::new(),
            camera_effects: Vec::new(),
        }
    }
}
