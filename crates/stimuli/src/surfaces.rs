//! The benchmark surfaces (sphere, ellipsoid, Gaussian bump, vase, the bunny, a mesh, a depth map) as
//! stimuli: a surface rendered under one light with a chosen reflectance model.
//!
//! Their lengths are fractions of the frame's shorter side, because benchmark objects are
//! framed, not placed in degrees; the frame itself still has a size in degrees.

use super::{Output, Stimulus, Targets, Typed};
use crate::error::{Error, Result};
use crate::light::Light;
use crate::params::{param_choice, stimulus_params, ParamSet};
use crate::reflectance::{BrdfModel, BrdfSpec, ReflectanceMap};
use crate::render::{render, RenderOptions};
use crate::surface::{self, Mesh, MeshShading, Surface};
use crate::visual_size::Geometry;

stimulus_params! {
    /// The light and reflectance of a rendered surface (shared by every surface stimulus, the
    /// hollow mask and the reflectance map).
    pub struct LightingParams {
        /// light direction (x,y,z | tilt=T,slant=S | name)
        light: Light = "above";
        /// reflectance model
        brdf: BrdfModel = BrdfModel::Lambertian;
        /// surface albedo
        albedo: f64 = BrdfSpec::default().albedo, range 0.0..=1.0;
        /// ambient level added everywhere (also the level in shadow)
        ambient: f64 = BrdfSpec::default().ambient, range 0.0..=1.0;
        /// specular strength (blinn-phong)
        specular: f64 = BrdfSpec::default().specular, range 0.0..=10.0;
        /// specular exponent (blinn-phong)
        shininess: f64 = BrdfSpec::default().shininess, range 1.0..=10000.0;
        /// facet slope spread in degrees (oren-nayar)
        roughness: f64 = BrdfSpec::default().roughness_deg, range 0.0..=90.0;
    }
}

impl LightingParams {
    /// The reflectance model these parameters name.
    pub fn brdf_spec(&self) -> BrdfSpec {
        BrdfSpec {
            model: self.brdf,
            albedo: self.albedo,
            ambient: self.ambient,
            specular: self.specular,
            shininess: self.shininess,
            roughness_deg: self.roughness,
        }
    }

    /// The reflectance map under the light.
    pub fn reflectance(&self) -> Result<Box<dyn ReflectanceMap>> {
        self.brdf_spec().build(self.light)
    }
}

stimulus_params! {
    /// What surrounds a rendered surface and whether it shadows itself.
    pub struct BackdropParams {
        /// luminance outside the object
        background: f64 = 0.0, range 0.0..=1.0;
        /// ray-march cast shadows over the heightfield
        cast_shadows: bool = false;
    }
}

impl BackdropParams {
    /// The render options these parameters give.
    pub fn render_options(&self) -> RenderOptions {
        RenderOptions {
            background: self.background,
            cast_shadows: self.cast_shadows,
        }
    }
}

/// Renders `surface` under `lighting` on `backdrop`.
fn render_surface(
    surface: Surface,
    lighting: &LightingParams,
    backdrop: &BackdropParams,
) -> Result<Output> {
    let reflectance = lighting.reflectance()?;
    let rendering = render(&surface, reflectance.as_ref(), &backdrop.render_options());
    let targets = Targets {
        labels: surface.mask.map(|&m| u16::from(m)),
        names: vec!["object".into()],
    };
    // The target is the object's silhouette against the backdrop: an occluding outline, so a
    // solve of the render takes it as the object's mask (see `io::RenderSidecar::silhouette`).
    let mut notes = serde_json::Map::new();
    notes.insert(crate::io::SILHOUETTE_NOTE.into(), true.into());
    Ok(Output::rendered(surface, rendering, targets, notes))
}

/// The frame's shorter side in pixels: the unit of the benchmark surfaces' lengths.
fn shorter_side(g: &Geometry) -> f64 {
    g.width.min(g.height) as f64
}

stimulus_params! {
    /// Parameters of [`sphere`].
    pub struct SphereParams {
        /// radius as a fraction of the frame's shorter side
        radius: f64 = 0.45, range 0.01..=5.0;
        /// light and reflectance
        flatten lighting: LightingParams {};
        /// background and cast shadows
        flatten backdrop: BackdropParams {};
    }
}

/// A hemisphere under one light, the classic shape-from-shading benchmark.
///
/// ```
/// use shadelab::ParamSet;
/// use shadelab::stimulus::{sphere, Pixels, SphereParams};
/// use shadelab::Geometry;
///
/// let g = Geometry { width: 9, height: 9, ppd: 1.0 };
/// let mut p = SphereParams::default();
/// p.lighting.light = "front".parse().unwrap();
/// let out = sphere(&p, &g).unwrap();
/// let Pixels::Gray(image) = out.pixels else { panic!() };
/// // Lit head-on with albedo 1, the nearest point of the sphere has luminance 1
/// // and the corner is background.
/// assert!((*image.get(4, 4) - 1.0).abs() < 1e-12);
/// assert_eq!(*image.get(0, 0), 0.0);
/// ```
pub fn sphere(p: &SphereParams, g: &Geometry) -> Result<Output> {
    p.validate()?;
    let surface = surface::sphere(g.width, g.height, p.radius * shorter_side(g))?;
    render_surface(surface, &p.lighting, &p.backdrop)
}

stimulus_params! {
    /// Parameters of [`ellipsoid`].
    pub struct EllipsoidParams {
        /// x semi-axis, fraction of the shorter side
        a: f64 = 0.45, range 0.01..=5.0;
        /// y semi-axis, fraction of the shorter side
        b: f64 = 0.3, range 0.01..=5.0;
        /// z semi-axis (depth), fraction of the shorter side
        c: f64 = 0.3, range 0.01..=5.0;
        /// light and reflectance
        flatten lighting: LightingParams {};
        /// background and cast shadows
        flatten backdrop: BackdropParams {};
    }
}

/// The front half of an ellipsoid.
pub fn ellipsoid(p: &EllipsoidParams, g: &Geometry) -> Result<Output> {
    p.validate()?;
    let side = shorter_side(g);
    let surface = surface::ellipsoid(g.width, g.height, p.a * side, p.b * side, p.c * side)?;
    render_surface(surface, &p.lighting, &p.backdrop)
}

stimulus_params! {
    /// Parameters of [`gaussian`].
    pub struct GaussianParams {
        /// peak height (negative: a dimple), fraction of the shorter side
        height: f64 = 0.12, range -5.0..=5.0;
        /// standard deviation, fraction of the shorter side
        sigma: f64 = 0.12, range 0.001..=5.0;
        /// light and reflectance
        flatten lighting: LightingParams {};
        /// background and cast shadows
        flatten backdrop: BackdropParams {};
    }
}

/// A Gaussian bump or dimple on a plane.
pub fn gaussian(p: &GaussianParams, g: &Geometry) -> Result<Output> {
    p.validate()?;
    let side = shorter_side(g);
    let surface = surface::gaussian(g.width, g.height, p.height * side, p.sigma * side, 0.0, 0.0)?;
    render_surface(surface, &p.lighting, &p.backdrop)
}

stimulus_params! {
    /// Parameters of [`vase`].
    pub struct VaseParams {
        /// light and reflectance
        flatten lighting: LightingParams {};
        /// background and cast shadows
        flatten backdrop: BackdropParams {};
    }
}

/// The vase of Zhang, Tsai, Cryer & Shah (1999), scaled to the frame.
pub fn vase(p: &VaseParams, g: &Geometry) -> Result<Output> {
    p.validate()?;
    let surface = surface::vase(g.width, g.height)?;
    render_surface(surface, &p.lighting, &p.backdrop)
}

stimulus_params! {
    /// Parameters of [`heightfield`].
    pub struct HeightfieldParams {
        /// the .npy depth map (H×W, pixel units)
        path: String = "";
        /// multiplies the depth (negative turns it hollow)
        scale: f64 = 1.0, range -1e6..=1e6;
        /// treat exact zeros as background
        zero_is_background: bool = true;
        /// light and reflectance
        flatten lighting: LightingParams {};
        /// background and cast shadows
        flatten backdrop: BackdropParams {};
    }
}

/// A depth map from a `.npy` file, rendered; `g` must have the map's size.
pub fn heightfield(p: &HeightfieldParams, g: &Geometry) -> Result<Output> {
    p.validate()?;
    if p.path.is_empty() {
        return Err(Error::invalid(
            "heightfield: give the depth map as its parameter path=FILE.npy",
        ));
    }
    let path = std::path::Path::new(&p.path);
    let depth = crate::io::read_image(path, crate::grid::DEFAULT_MAX_PIXELS)?;
    if depth.width() != g.width || depth.height() != g.height {
        let mismatch = crate::grid::size_mismatch(
            "depth map is",
            (depth.width(), depth.height()),
            "the requested size is",
            (g.width, g.height),
        );
        return Err(Error::format(
            path,
            format!("{mismatch} (omit the size to use the map's own)"),
        ));
    }
    let domain = if p.zero_is_background {
        surface::DepthDomain::NonZero
    } else {
        surface::DepthDomain::All
    };
    let scale = p.scale;
    let surface = surface::depth_surface(depth.map(|z| z * scale), domain)
        .map_err(|e| Error::format(path, e.to_string()))?;
    render_surface(surface, &p.lighting, &p.backdrop)
}

/// The size of the depth map that `p` names, if it names one.
fn depth_map_shape(p: &HeightfieldParams) -> Result<Option<(usize, usize)>> {
    if p.path.is_empty() {
        return Ok(None);
    }
    let depth = crate::io::read_image(
        std::path::Path::new(&p.path),
        crate::grid::DEFAULT_MAX_PIXELS,
    )?;
    Ok(Some((depth.width(), depth.height())))
}

param_choice! {
    /// How a rasterised mesh is shaded.
    pub enum MeshNormals {
        /// Interpolated vertex normals.
        Smooth = "smooth",
        /// One normal per face.
        Flat = "flat",
    }
}

stimulus_params! {
    /// How a mesh is turned and framed.
    pub struct ViewParams {
        /// turn about the vertical axis in degrees (front toward +x)
        yaw: f64 = 0.0, range -360.0..=360.0;
        /// tip about the horizontal axis in degrees (top toward the viewer)
        pitch: f64 = 0.0, range -360.0..=360.0;
        /// turn in the image plane in degrees (counter-clockwise)
        roll: f64 = 0.0, range -360.0..=360.0;
        /// fraction of the frame the object's bounding box fills
        fill: f64 = 0.85, range 0.01..=surface::MAX_FILL;
        /// interpolated vertex normals or one normal per face
        shading: MeshNormals = MeshNormals::Smooth;
    }
}

stimulus_params! {
    /// Parameters of [`bunny`].
    pub struct BunnyParams {
        /// view
        flatten view: ViewParams {};
        /// light and reflectance
        flatten lighting: LightingParams {};
        /// background and cast shadows
        flatten backdrop: BackdropParams {};
    }
}

/// The Stanford Bunny (built in), rasterised under any view.
pub fn bunny(p: &BunnyParams, g: &Geometry) -> Result<Output> {
    p.validate()?;
    let mesh = Mesh::from_ply(BUNNY_PLY, std::path::Path::new("bun_zipper_res3.ply"))?;
    let surface = rasterize_mesh(&mesh, &p.view, g)?;
    render_surface(surface, &p.lighting, &p.backdrop)
}

stimulus_params! {
    /// Parameters of [`mesh`].
    pub struct MeshParams {
        /// the mesh file (.ply ASCII or binary, or .obj)
        path: String = "";
        /// view
        flatten view: ViewParams {};
        /// light and reflectance
        flatten lighting: LightingParams {};
        /// background and cast shadows
        flatten backdrop: BackdropParams {};
    }
}

/// A triangle mesh (`.ply` or `.obj`) rasterised orthographically under any view.
pub fn mesh(p: &MeshParams, g: &Geometry) -> Result<Output> {
    p.validate()?;
    if p.path.is_empty() {
        return Err(Error::invalid(
            "mesh: give the mesh file as its parameter path=FILE.ply (or .obj)",
        ));
    }
    let surface = rasterize_mesh(&Mesh::load(&p.path)?, &p.view, g)
        .map_err(|e| Error::format(&p.path, e.to_string()))?;
    render_surface(surface, &p.lighting, &p.backdrop)
}

/// The surfaces of the core as stimuli.
pub fn all() -> Vec<Box<dyn Stimulus>> {
    const SIZE: (f64, f64) = (8.0, 8.0);
    const PPD: f64 = 32.0;
    vec![
        Typed::boxed(
            "sphere",
            "a hemisphere under one light: the classic shape-from-shading benchmark",
            SIZE,
            PPD,
            |p, g, _| sphere(p, g),
        ),
        Typed::boxed(
            "ellipsoid",
            "the front half of an ellipsoid (semi-axes a, b, c)",
            SIZE,
            PPD,
            |p, g, _| ellipsoid(p, g),
        ),
        Typed::boxed(
            "gaussian",
            "a Gaussian bump (height > 0) or dimple (height < 0) on a plane",
            SIZE,
            PPD,
            |p, g, _| gaussian(p, g),
        ),
        Typed::boxed(
            "vase",
            "the vase of Zhang, Tsai, Cryer & Shah (1999), scaled to the frame",
            SIZE,
            PPD,
            |p, g, _| vase(p, g),
        ),
        Box::new(Typed {
            natural: depth_map_shape,
            ..Typed::new(
                "heightfield",
                "a depth map from a .npy file (pixel units; its size sets the frame)",
                SIZE,
                PPD,
                |p, g, _| heightfield(p, g),
            )
        }),
        Typed::boxed(
            "bunny",
            "the Stanford Bunny (built in, 1,889 vertices), rasterised under any view",
            SIZE,
            PPD,
            |p, g, _| bunny(p, g),
        ),
        Typed::boxed(
            "mesh",
            "a triangle mesh (.ply or .obj) rasterised orthographically under any view",
            SIZE,
            PPD,
            |p, g, _| mesh(p, g),
        ),
    ]
}

/// The Stanford Bunny at its coarsest resolution (Stanford 3D Scanning Repository, Stanford
/// Computer Graphics Laboratory; Turk & Levoy 1994; credited in tests/data/README.md).
const BUNNY_PLY: &[u8] = include_bytes!("../assets/bun_zipper_res3.ply");

fn rasterize_mesh(mesh: &Mesh, view: &ViewParams, g: &Geometry) -> Result<Surface> {
    let rotation = surface::view_rotation(view.yaw, view.pitch, view.roll)?;
    let shading = match view.shading {
        MeshNormals::Flat => MeshShading::Flat,
        MeshNormals::Smooth => MeshShading::Smooth,
    };
    mesh.rasterize_with(g.width, g.height, &rotation, view.fill, shading)
}
