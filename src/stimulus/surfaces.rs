//! The benchmark surfaces (sphere, ellipsoid, Gaussian bump, vase, the bunny, a mesh, a depth map) as
//! stimuli: a surface rendered under one light with a chosen reflectance model.
//!
//! Their lengths are fractions of the frame's shorter side, because benchmark objects are
//! framed, not placed in degrees; the frame itself still has a size in degrees.

use super::{Info, Output, Pixels, Request, Stimulus, SurfaceLayers, Targets};
use crate::error::{Error, Result};
use crate::params::{ParamSpec, Params};
use crate::reflectance::{BrdfSpec, ReflectanceMap, BRDF_NAMES};
use crate::render::{render, RenderOptions};
use crate::surface::{self, Mesh, MeshShading, Surface};

/// Parameters shared by every rendered surface: light, reflectance and background.
pub fn lighting_params(default_light: &'static str, default_background: f64) -> Vec<ParamSpec> {
    let d = BrdfSpec::default();
    vec![
        ParamSpec::light(
            "light",
            default_light,
            "light direction (x,y,z | tilt=T,slant=S | name)",
        ),
        ParamSpec::choice("brdf", "lambertian", BRDF_NAMES, "reflectance model"),
        ParamSpec::number("albedo", d.albedo, 0.0, 1.0, "surface albedo"),
        ParamSpec::number(
            "ambient",
            d.ambient,
            0.0,
            1.0,
            "ambient level added everywhere (also the level in shadow)",
        ),
        ParamSpec::number(
            "specular",
            d.specular,
            0.0,
            10.0,
            "specular strength (blinn-phong)",
        ),
        ParamSpec::number(
            "shininess",
            d.shininess,
            1.0,
            10000.0,
            "specular exponent (blinn-phong)",
        ),
        ParamSpec::number(
            "roughness",
            d.roughness_deg,
            0.0,
            90.0,
            "facet slope spread in degrees (oren-nayar)",
        ),
        ParamSpec::number(
            "background",
            default_background,
            0.0,
            1.0,
            "luminance outside the object",
        ),
        ParamSpec::boolean(
            "cast_shadows",
            false,
            "ray-march cast shadows over the heightfield",
        ),
    ]
}

/// The reflectance map that the lighting parameters of [`lighting_params`] describe.
pub fn reflectance_from_params(params: &Params) -> Result<Box<dyn ReflectanceMap>> {
    BrdfSpec {
        model: params.str("brdf")?.to_string(),
        albedo: params.f64("albedo")?,
        ambient: params.f64("ambient")?,
        specular: params.f64("specular")?,
        shininess: params.f64("shininess")?,
        roughness_deg: params.f64("roughness")?,
    }
    .build(params.light("light")?)
}

/// The background and cast-shadow options of [`lighting_params`].
pub fn render_options_from_params(params: &Params) -> Result<RenderOptions> {
    Ok(RenderOptions {
        background: params.f64("background")?,
        cast_shadows: params.bool("cast_shadows")?,
    })
}

/// Renders `surface` with the lighting parameters of [`lighting_params`].
pub fn render_surface(surface: Surface, params: &Params) -> Result<Output> {
    let reflectance = reflectance_from_params(params)?;
    let rendering = render(
        &surface,
        reflectance.as_ref(),
        &render_options_from_params(params)?,
    );
    let labels = surface.mask.map(|&m| u16::from(m));
    Ok(Output {
        pixels: Pixels::Gray(rendering.image),
        targets: Some(Targets {
            labels,
            names: vec!["object".into()],
        }),
        surface: Some(SurfaceLayers {
            depth: surface.depth,
            normals: surface.normals,
            mask: surface.mask,
            albedo: None,
            shading: Some(rendering.shading),
        }),
        svg: None,
        notes: Default::default(),
    })
}

type Build = fn(&Request, f64) -> Result<Surface>;
type NaturalShape = fn(&Params) -> Result<Option<(usize, usize)>>;

struct SurfaceStimulus {
    name: &'static str,
    summary: &'static str,
    params: fn() -> Vec<ParamSpec>,
    build: Build,
    natural: Option<NaturalShape>,
}

impl Stimulus for SurfaceStimulus {
    fn info(&self) -> Info {
        let mut params = (self.params)();
        params.extend(lighting_params("above", 0.0));
        Info {
            name: self.name,
            summary: self.summary,
            params,
            default_visual_size: (8.0, 8.0),
            default_ppd: 32.0,
        }
    }

    fn generate(&self, request: &Request) -> Result<Output> {
        let g = &request.geometry;
        let side = g.width.min(g.height) as f64;
        let surface = (self.build)(request, side)?;
        render_surface(surface, &request.params)
    }

    fn natural_shape(&self, params: &Params) -> Result<Option<(usize, usize)>> {
        match self.natural {
            Some(f) => f(params),
            None => Ok(None),
        }
    }
}

fn depth_map_shape(params: &Params) -> Result<Option<(usize, usize)>> {
    let path = params.str("path")?;
    if path.is_empty() {
        return Ok(None);
    }
    let depth = crate::io::read_image(std::path::Path::new(path), crate::grid::DEFAULT_MAX_PIXELS)?;
    Ok(Some((depth.width(), depth.height())))
}

/// The surfaces of the core as stimuli.
pub fn all() -> Vec<Box<dyn Stimulus>> {
    vec![
        Box::new(SurfaceStimulus {
            name: "sphere",
            summary: "a hemisphere under one light: the classic shape-from-shading benchmark",
            params: || {
                vec![ParamSpec::number(
                    "radius",
                    0.45,
                    0.01,
                    5.0,
                    "radius as a fraction of the frame's shorter side",
                )]
            },
            build: |r, side| {
                let g = &r.geometry;
                surface::sphere(g.width, g.height, r.params.f64("radius")? * side)
            },
            natural: None,
        }),
        Box::new(SurfaceStimulus {
            name: "ellipsoid",
            summary: "the front half of an ellipsoid (semi-axes a, b, c)",
            params: || {
                vec![
                    ParamSpec::number(
                        "a",
                        0.45,
                        0.01,
                        5.0,
                        "x semi-axis, fraction of the shorter side",
                    ),
                    ParamSpec::number(
                        "b",
                        0.3,
                        0.01,
                        5.0,
                        "y semi-axis, fraction of the shorter side",
                    ),
                    ParamSpec::number(
                        "c",
                        0.3,
                        0.01,
                        5.0,
                        "z semi-axis (depth), fraction of the shorter side",
                    ),
                ]
            },
            build: |r, side| {
                let (g, p) = (&r.geometry, &r.params);
                surface::ellipsoid(
                    g.width,
                    g.height,
                    p.f64("a")? * side,
                    p.f64("b")? * side,
                    p.f64("c")? * side,
                )
            },
            natural: None,
        }),
        Box::new(SurfaceStimulus {
            name: "gaussian",
            summary: "a Gaussian bump (height > 0) or dimple (height < 0) on a plane",
            params: || {
                vec![
                    ParamSpec::number(
                        "height",
                        0.12,
                        -5.0,
                        5.0,
                        "peak height (negative: a dimple), fraction of the shorter side",
                    ),
                    ParamSpec::number(
                        "sigma",
                        0.12,
                        0.001,
                        5.0,
                        "standard deviation, fraction of the shorter side",
                    ),
                ]
            },
            build: |r, side| {
                let (g, p) = (&r.geometry, &r.params);
                surface::gaussian(
                    g.width,
                    g.height,
                    p.f64("height")? * side,
                    p.f64("sigma")? * side,
                    0.0,
                    0.0,
                )
            },
            natural: None,
        }),
        Box::new(SurfaceStimulus {
            name: "vase",
            summary: "the vase of Zhang, Tsai, Cryer & Shah (1999), scaled to the frame",
            params: Vec::new,
            build: |r, _| surface::vase(r.geometry.width, r.geometry.height),
            natural: None,
        }),
        Box::new(SurfaceStimulus {
            name: "heightfield",
            summary: "a depth map from a .npy file (pixel units; its size sets the frame)",
            params: || {
                vec![
                    ParamSpec::text("path", "", "the .npy depth map (H×W, pixel units)"),
                    ParamSpec::number(
                        "scale",
                        1.0,
                        -1e6,
                        1e6,
                        "multiplies the depth (negative turns it hollow)",
                    ),
                    ParamSpec::boolean(
                        "zero_is_background",
                        true,
                        "treat exact zeros as background",
                    ),
                ]
            },
            build: |r, _| {
                let p = &r.params;
                let path = p.str("path")?;
                if path.is_empty() {
                    return Err(Error::invalid(
                        "heightfield: give the depth map with --set path=FILE.npy",
                    ));
                }
                let path = std::path::Path::new(path);
                let depth = crate::io::read_image(path, crate::grid::DEFAULT_MAX_PIXELS)?;
                let g = &r.geometry;
                if depth.width() != g.width || depth.height() != g.height {
                    return Err(Error::format(
                        path,
                        format!(
                            "depth map is {}x{} but the requested size is {}x{} (omit the size to use the map's own)",
                            depth.width(),
                            depth.height(),
                            g.width,
                            g.height
                        ),
                    ));
                }
                let domain = if p.bool("zero_is_background")? {
                    surface::DepthDomain::NonZero
                } else {
                    surface::DepthDomain::All
                };
                let scale = p.f64("scale")?;
                surface::depth_surface(depth.map(|z| z * scale), domain)
                    .map_err(|e| Error::format(path, e.to_string()))
            },
            natural: Some(depth_map_shape),
        }),
        Box::new(SurfaceStimulus {
            name: "bunny",
            summary: "the Stanford Bunny (built in, 1,889 vertices), rasterised under any view",
            params: view_params,
            build: |r, _| {
                let mesh = Mesh::from_ply(BUNNY_PLY, std::path::Path::new("bun_zipper_res3.ply"))?;
                rasterize_mesh(&mesh, r)
            },
            natural: None,
        }),
        Box::new(SurfaceStimulus {
            name: "mesh",
            summary: "a triangle mesh (.ply or .obj) rasterised orthographically under any view",
            params: || {
                let mut v = vec![ParamSpec::text(
                    "path",
                    "",
                    "the mesh file (.ply ASCII or binary, or .obj)",
                )];
                v.extend(view_params());
                v
            },
            build: |r, _| {
                let path = r.params.str("path")?;
                if path.is_empty() {
                    return Err(Error::invalid(
                        "mesh: give the mesh file with --set path=FILE.ply (or .obj)",
                    ));
                }
                rasterize_mesh(&Mesh::load(path)?, r)
                    .map_err(|e| Error::format(path, e.to_string()))
            },
            natural: None,
        }),
    ]
}

/// The Stanford Bunny at its coarsest resolution (Stanford 3D Scanning Repository, Stanford
/// Computer Graphics Laboratory; Turk & Levoy 1994; credited in tests/data/README.md).
const BUNNY_PLY: &[u8] = include_bytes!("../../tests/data/bun_zipper_res3.ply");

fn view_params() -> Vec<ParamSpec> {
    vec![
        ParamSpec::number(
            "yaw",
            0.0,
            -360.0,
            360.0,
            "turn about the vertical axis in degrees (front toward +x)",
        ),
        ParamSpec::number(
            "pitch",
            0.0,
            -360.0,
            360.0,
            "tip about the horizontal axis in degrees (top toward the viewer)",
        ),
        ParamSpec::number(
            "roll",
            0.0,
            -360.0,
            360.0,
            "turn in the image plane in degrees (counter-clockwise)",
        ),
        ParamSpec::number(
            "fill",
            0.85,
            0.01,
            surface::MAX_FILL,
            "fraction of the frame the object's bounding box fills",
        ),
        ParamSpec::choice(
            "shading",
            "smooth",
            &["smooth", "flat"],
            "interpolated vertex normals or one normal per face",
        ),
    ]
}

fn rasterize_mesh(mesh: &Mesh, r: &Request) -> Result<Surface> {
    let p = &r.params;
    let view = surface::view_rotation(p.f64("yaw")?, p.f64("pitch")?, p.f64("roll")?)?;
    let shading = if p.str("shading")? == "flat" {
        MeshShading::Flat
    } else {
        MeshShading::Smooth
    };
    mesh.rasterize_with(
        r.geometry.width,
        r.geometry.height,
        &view,
        p.f64("fill")?,
        shading,
    )
}
