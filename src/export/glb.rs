//! One binary glTF (GLB) of export cells: a node and mesh per cell with two primitives
//! (surface, skirt) over shared positions and texture coordinates, the cell's texture
//! embedded as stored, an unlit material (`KHR_materials_unlit`); cells prepared with
//! [`ExportCell::make_lit`] get a lit material instead: `NORMAL` and `TANGENT` from the
//! exported positions ([`super::normals::vertex_frames`]) and the tangent-space normal map.

use std::collections::BTreeMap;

use gltf::json;
use json::validation::Checked::Valid;
use json::validation::USize64;

use super::ExportCell;
use crate::error::{Error, Result};

/// Writes `cells` as one GLB; `to_local(cell, vertex)` gives a vertex's position in the
/// glTF frame (metres, y up; the caller's choice of origin keeps the f32 values small; a
/// non-finite value is an error); `extras` goes
/// into the glTF's top-level `extras`. POSITION accessors carry min/max; every buffer view
/// is 4-byte aligned.
pub fn write_glb(
    cells: &[ExportCell],
    to_local: &dyn Fn(usize, usize) -> [f64; 3],
    extras: &serde_json::Value,
) -> Result<Vec<u8>> {
    let mut glb = GlbBuilder::new(cells);
    let mut nodes = Vec::with_capacity(cells.len());
    for (ci, cell) in cells.iter().enumerate() {
        let local = local_positions(cell, |v| to_local(ci, v))?;
        nodes.push(glb.push_cell(cell, &local));
    }
    glb.finish(nodes, extras)
}

/// A cell's positions in the glTF frame as f32; an error names a cell with a non-finite one.
fn local_positions(
    cell: &ExportCell,
    to_local: impl Fn(usize) -> [f64; 3],
) -> Result<Vec<[f32; 3]>> {
    let local: Vec<[f32; 3]> = (0..cell.positions.len())
        .map(|v| {
            let q = to_local(v);
            [q[0] as f32, q[1] as f32, q[2] as f32]
        })
        .collect();
    if local.iter().flatten().any(|v| !v.is_finite()) {
        return Err(Error::BadOption(format!(
            "cell {}: a position is not finite in the export frame",
            cell.id
        )));
    }
    Ok(local)
}

/// A cell's lit-material pieces: its normal and tangent accessors and normal-map texture.
type LitParts = (
    json::Index<json::Accessor>,
    json::Index<json::Accessor>,
    json::Index<json::Texture>,
);

/// The glTF document and binary chunk being written, cell by cell.
struct GlbBuilder {
    root: json::Root,
    bin: Vec<u8>,
    /// Trilinear sampler of colour and normal textures.
    sampler: json::Index<json::texture::Sampler>,
    /// Unfiltered sampler of property textures (`sampler` when no cell has metadata).
    nearest: json::Index<json::texture::Sampler>,
    property_textures: Vec<serde_json::Value>,
}

impl GlbBuilder {
    /// The document's asset, extensions and samplers for `cells`.
    fn new(cells: &[ExportCell]) -> GlbBuilder {
        let mut root = json::Root::default();
        root.asset.generator = Some(format!("cliffmap {}", env!("CARGO_PKG_VERSION")));
        if cells.iter().any(|c| c.normal_png.is_none()) {
            root.extensions_used.push("KHR_materials_unlit".into());
        }
        let sampler = root.push(json::texture::Sampler {
            mag_filter: Some(Valid(json::texture::MagFilter::Linear)),
            min_filter: Some(Valid(json::texture::MinFilter::LinearMipmapLinear)),
            wrap_s: Valid(json::texture::WrappingMode::ClampToEdge),
            wrap_t: Valid(json::texture::WrappingMode::ClampToEdge),
            ..Default::default()
        });
        // property textures are sampled without filtering (a texel's bytes form one value)
        // (only when some cell has metadata: an unused sampler is reported by validators)
        let nearest = if cells.iter().any(|c| c.metadata.is_some()) {
            root.push(json::texture::Sampler {
                mag_filter: Some(Valid(json::texture::MagFilter::Nearest)),
                min_filter: Some(Valid(json::texture::MinFilter::Nearest)),
                wrap_s: Valid(json::texture::WrappingMode::ClampToEdge),
                wrap_t: Valid(json::texture::WrappingMode::ClampToEdge),
                ..Default::default()
            })
        } else {
            sampler
        };
        GlbBuilder {
            root,
            bin: Vec::new(),
            sampler,
            nearest,
            property_textures: Vec::new(),
        }
    }

    /// One cell: its vertices, textures, material, property texture, primitives (surface,
    /// skirt), mesh and node.
    fn push_cell(&mut self, cell: &ExportCell, local: &[[f32; 3]]) -> json::Index<json::Node> {
        let (mut lo, mut hi) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
        for p in local {
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        // (the two views first, then their accessors, as the files have always been laid out)
        let pos_view = push_view(
            &mut self.root,
            &mut self.bin,
            bytes_of_f32(local.iter().flatten()),
            Some(json::buffer::Target::ArrayBuffer),
        );
        let uv_view = push_view(
            &mut self.root,
            &mut self.bin,
            bytes_of_f32(cell.uvs.iter().flatten()),
            Some(json::buffer::Target::ArrayBuffer),
        );
        let pos = self.root.push(accessor(
            pos_view,
            local.len(),
            json::accessor::ComponentType::F32,
            json::accessor::Type::Vec3,
            Some((lo, hi)),
        ));
        let uv = self.root.push(accessor(
            uv_view,
            cell.uvs.len(),
            json::accessor::ComponentType::F32,
            json::accessor::Type::Vec2,
            None,
        ));
        let lit = cell
            .normal_png
            .as_ref()
            .map(|png| self.push_lit(cell, local, png));
        let material = self.push_material(cell, lit);
        let property_texture = self.push_property_texture(cell);
        let primitives = self.primitives(cell, pos, uv, lit, material, property_texture);
        let mesh = self.root.push(json::Mesh {
            extensions: None,
            extras: Default::default(),
            name: Some(cell.id.clone()),
            primitives,
            weights: None,
        });
        self.root.push(json::Node {
            mesh: Some(mesh),
            name: Some(cell.id.clone()),
            ..Default::default()
        })
    }

    /// The lit variant: vertex frames of the exported positions and the baked normal map.
    fn push_lit(&mut self, cell: &ExportCell, local: &[[f32; 3]], png: &[u8]) -> LitParts {
        let p: Vec<glam::DVec3> = local
            .iter()
            .map(|q| glam::DVec3::new(q[0] as f64, q[1] as f64, q[2] as f64))
            .collect();
        let f = super::normals::vertex_frames(&p, &cell.uvs, &cell.surface);
        let normals: Vec<f32> = f
            .normals
            .iter()
            .flat_map(|n| n.to_array().map(|v| v as f32))
            .collect();
        let tangents: Vec<f32> = f
            .tangents
            .iter()
            .flat_map(|t| t.map(|v| v as f32))
            .collect();
        // (both views first, then both accessors)
        let nv = push_view(
            &mut self.root,
            &mut self.bin,
            bytes_of_f32(normals.iter()),
            Some(json::buffer::Target::ArrayBuffer),
        );
        let tv = push_view(
            &mut self.root,
            &mut self.bin,
            bytes_of_f32(tangents.iter()),
            Some(json::buffer::Target::ArrayBuffer),
        );
        let normal = self.root.push(accessor(
            nv,
            f.normals.len(),
            json::accessor::ComponentType::F32,
            json::accessor::Type::Vec3,
            None,
        ));
        let tangent = self.root.push(accessor(
            tv,
            f.tangents.len(),
            json::accessor::ComponentType::F32,
            json::accessor::Type::Vec4,
            None,
        ));
        let texture = push_texture(
            &mut self.root,
            &mut self.bin,
            png.to_vec(),
            "image/png",
            format!("{} normal (tangent space)", cell.id),
            self.sampler,
        );
        (normal, tangent, texture)
    }

    /// The cell's colour texture and its material: lit with the normal map, else unlit.
    fn push_material(
        &mut self,
        cell: &ExportCell,
        lit: Option<LitParts>,
    ) -> json::Index<json::Material> {
        let texture = push_texture(
            &mut self.root,
            &mut self.bin,
            cell.texture_bytes.clone(),
            cell.texture_mime,
            format!("{} {}", cell.id, cell.texture.name()),
            self.sampler,
        );
        self.root.push(json::Material {
            name: Some(cell.id.clone()),
            pbr_metallic_roughness: json::material::PbrMetallicRoughness {
                base_color_texture: Some(json::texture::Info {
                    index: texture,
                    tex_coord: 0,
                    extensions: None,
                    extras: Default::default(),
                }),
                metallic_factor: json::material::StrengthFactor(0.0),
                roughness_factor: json::material::StrengthFactor(1.0),
                ..Default::default()
            },
            normal_texture: lit.map(|(_, _, index)| json::material::NormalTexture {
                index,
                scale: 1.0,
                tex_coord: 0,
                extensions: None,
                extras: Default::default(),
            }),
            extensions: lit.is_none().then(|| json::extensions::material::Material {
                unlit: Some(json::extensions::material::Unlit {}),
                ..Default::default()
            }),
            ..Default::default()
        })
    }

    /// Per-texel metadata: the cell's property texture (stretch, photo share), by its index
    /// among the document's property textures.
    fn push_property_texture(&mut self, cell: &ExportCell) -> Option<usize> {
        let m = cell.metadata.as_ref()?;
        let stretch = push_texture(
            &mut self.root,
            &mut self.bin,
            m.stretch_png.clone(),
            "image/png",
            format!("{} stretch", cell.id),
            self.nearest,
        );
        let share = m.share_png.as_ref().map(|png| {
            push_texture(
                &mut self.root,
                &mut self.bin,
                png.clone(),
                "image/png",
                format!("{} photo share", cell.id),
                self.nearest,
            )
            .value()
        });
        self.property_textures
            .push(super::metadata::property_texture(stretch.value(), share));
        Some(self.property_textures.len() - 1)
    }

    /// The cell's primitives: surface and skirt triangles (each if any) over the shared
    /// attributes; the surface carries the property texture.
    fn primitives(
        &mut self,
        cell: &ExportCell,
        pos: json::Index<json::Accessor>,
        uv: json::Index<json::Accessor>,
        lit: Option<LitParts>,
        material: json::Index<json::Material>,
        property_texture: Option<usize>,
    ) -> Vec<json::mesh::Primitive> {
        let mut primitives = Vec::new();
        for (k, tris) in [&cell.surface, &cell.skirt].into_iter().enumerate() {
            if tris.is_empty() {
                continue;
            }
            let idx: Vec<u8> = tris
                .iter()
                .flatten()
                .flat_map(|i| i.to_le_bytes())
                .collect();
            let view = push_view(
                &mut self.root,
                &mut self.bin,
                idx,
                Some(json::buffer::Target::ElementArrayBuffer),
            );
            let indices = self.root.push(accessor(
                view,
                tris.len() * 3,
                json::accessor::ComponentType::U32,
                json::accessor::Type::Scalar,
                None,
            ));
            let mut attributes = BTreeMap::new();
            attributes.insert(Valid(json::mesh::Semantic::Positions), pos);
            attributes.insert(Valid(json::mesh::Semantic::TexCoords(0)), uv);
            if let Some((normal, tangent, _)) = lit {
                attributes.insert(Valid(json::mesh::Semantic::Normals), normal);
                attributes.insert(Valid(json::mesh::Semantic::Tangents), tangent);
            }
            // (the surface primitive carries the metadata)
            let extensions = property_texture.filter(|_| k == 0).map(|i| {
                let mut e = json::extensions::mesh::Primitive::default();
                e.others.insert(
                    "EXT_structural_metadata".into(),
                    serde_json::json!({"propertyTextures": [i]}),
                );
                e
            });
            primitives.push(json::mesh::Primitive {
                attributes,
                extensions,
                extras: Default::default(),
                indices: Some(indices),
                material: Some(material),
                mode: Valid(json::mesh::Mode::Triangles),
                targets: None,
            });
        }
        primitives
    }

    /// The scene of `nodes`, the metadata schema, the buffer and `extras`, as GLB bytes.
    fn finish(
        mut self,
        nodes: Vec<json::Index<json::Node>>,
        extras: &serde_json::Value,
    ) -> Result<Vec<u8>> {
        let root = &mut self.root;
        let scene = root.push(json::Scene {
            extensions: None,
            extras: Default::default(),
            name: None,
            nodes,
        });
        root.scene = Some(scene);
        if !self.property_textures.is_empty() {
            root.extensions_used.push("EXT_structural_metadata".into());
            let mut e = json::extensions::root::Root::default();
            e.others.insert(
                "EXT_structural_metadata".into(),
                serde_json::json!({
                    "schema": super::metadata::schema(),
                    "propertyTextures": self.property_textures,
                }),
            );
            root.extensions = Some(e);
        }
        root.buffers.push(json::Buffer {
            byte_length: USize64(self.bin.len() as u64),
            extensions: None,
            extras: Default::default(),
            name: None,
            uri: None,
        });
        root.extras = Some(
            serde_json::value::to_raw_value(extras)
                .map_err(|e| Error::BadOption(format!("glTF extras: {e}")))?,
        );
        let mut text = json::serialize::to_vec(&*root)
            .map_err(|e| Error::BadOption(format!("glTF JSON: {e}")))?;
        while text.len() % 4 != 0 {
            text.push(b' ');
        }
        let glb = gltf::binary::Glb {
            header: gltf::binary::Header {
                magic: *b"glTF",
                version: 2,
                length: 0,
            },
            json: std::borrow::Cow::Owned(text),
            bin: Some(std::borrow::Cow::Owned(self.bin)),
        };
        glb.to_vec()
            .map_err(|e| Error::BadOption(format!("GLB: {e}")))
    }
}

/// Embeds the image `bytes` (media type `mime`) and adds a texture of it with `sampler`.
fn push_texture(
    root: &mut json::Root,
    bin: &mut Vec<u8>,
    bytes: Vec<u8>,
    mime: &str,
    name: String,
    sampler: json::Index<json::texture::Sampler>,
) -> json::Index<json::Texture> {
    let view = push_view(root, bin, bytes, None);
    let image = root.push(json::Image {
        buffer_view: Some(view),
        mime_type: Some(json::image::MimeType(mime.into())),
        name: Some(name),
        uri: None,
        extensions: None,
        extras: Default::default(),
    });
    root.push(json::Texture {
        name: None,
        sampler: Some(sampler),
        source: image,
        extensions: None,
        extras: Default::default(),
    })
}

/// Appends `bytes` (padded to 4 bytes) to the binary chunk as a new buffer view.
fn push_view(
    root: &mut json::Root,
    bin: &mut Vec<u8>,
    bytes: Vec<u8>,
    target: Option<json::buffer::Target>,
) -> json::Index<json::buffer::View> {
    let offset = bin.len();
    let len = bytes.len();
    bin.extend(bytes);
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    root.push(json::buffer::View {
        buffer: json::Index::new(0),
        byte_length: USize64(len as u64),
        byte_offset: Some(USize64(offset as u64)),
        byte_stride: None,
        extensions: None,
        extras: Default::default(),
        name: None,
        target: target.map(Valid),
    })
}

fn accessor(
    view: json::Index<json::buffer::View>,
    count: usize,
    component: json::accessor::ComponentType,
    type_: json::accessor::Type,
    bounds: Option<([f32; 3], [f32; 3])>,
) -> json::Accessor {
    json::Accessor {
        buffer_view: Some(view),
        byte_offset: Some(USize64(0)),
        count: USize64(count as u64),
        component_type: Valid(json::accessor::GenericComponentType(component)),
        extensions: None,
        extras: Default::default(),
        type_: Valid(type_),
        min: bounds.map(|b| json::Value::from(b.0.to_vec())),
        max: bounds.map(|b| json::Value::from(b.1.to_vec())),
        name: None,
        normalized: false,
        sparse: None,
    }
}

fn bytes_of_f32<'a>(v: impl Iterator<Item = &'a f32>) -> Vec<u8> {
    v.flat_map(|x| x.to_le_bytes()).collect()
}
