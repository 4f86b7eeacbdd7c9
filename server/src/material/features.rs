//! What a program's generated code must hold: the optional parts of a
//! closure (edge tint, haze, fuzz, emission, …), each generated only when
//! a definition of the program uses it. The back end (`back`) and the
//! packing (`pack`) both shape their code by it.

use super::tree::{Builtin, Definition, ExprId, ExprKind, Field, NodeKind, Value};

/// The optional parts of a closure, each generated only when a definition
/// of the program uses it.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Features {
    /// F90 other than white, or a specular weight other than 1.
    pub edge: bool,
    pub haze: bool,
    pub fuzz: bool,
    pub emission: bool,
    /// A layer whose top absorbs (thickness and transmission colour).
    pub absorption: bool,
    /// A dielectric that transmits (`transmission_weight`): refraction
    /// into solids and light through thin walls (`shaders/lib/btdf.wgsl`).
    pub transmission: bool,
    /// A definition with multiple-scattering compensation (applied where
    /// its instance says so: `quality.energy_compensation`).
    pub compensated: bool,
    /// A texture is sampled (the texture bindings and helpers).
    pub textures: bool,
    /// A slab sets its own `normal` (each closure carries one).
    pub normal: bool,
    /// A thin film over the specular lobe (`shaders/lib/iridescence.wgsl`).
    pub thin_film: bool,
    /// A slab stretches its GGX lobe (`specular_roughness_anisotropy`):
    /// each closure carries its anisotropy and direction.
    pub anisotropy: bool,
}

impl Features {
    pub fn of(definitions: &[Definition]) -> Features {
        let mut f = Features::default();
        for d in definitions {
            for node in &d.nodes {
                let NodeKind::Slab(slab) = &node.kind else { continue };
                let set = |field: Field| slab.get(field).is_some_and(|e| !is_const(d, e, field.default()));
                f.edge |= set(Field::SpecularEdgeColor) || set(Field::SpecularWeight);
                f.haze |= set(Field::HazeWeight);
                f.fuzz |= set(Field::FuzzWeight);
                f.emission |= set(Field::EmissionLuminance);
                f.absorption |= set(Field::Thickness) && (set(Field::TransmissionColor) || set(Field::MeanFreePath));
                f.normal |= slab.get(Field::Normal).is_some();
                f.transmission |= set(Field::TransmissionWeight);
                f.thin_film |= set(Field::ThinFilmWeight);
                f.anisotropy |= set(Field::SpecularAnisotropy);
            }
            f.textures |= d.exprs.iter().any(|e| matches!(e.kind, ExprKind::Call(Builtin::Sample | Builtin::NormalMap, _)));
            // Compensation scales F0 and F90 alike: F90 must be a field.
            f.compensated |= d.energy_compensation;
            f.edge |= d.energy_compensation;
        }
        f
    }

    /// The names of the features on, for reports and the module's header.
    pub fn names(self) -> Vec<&'static str> {
        [
            (self.edge, "edge"),
            (self.haze, "haze"),
            (self.fuzz, "fuzz"),
            (self.emission, "emission"),
            (self.absorption, "absorption"),
            (self.transmission, "transmission"),
            (self.compensated, "energy compensation"),
            (self.textures, "textures"),
            (self.normal, "normal"),
            (self.thin_film, "thin film"),
            (self.anisotropy, "anisotropy"),
        ]
        .into_iter()
        .filter_map(|(on, name)| on.then_some(name))
        .collect()
    }
}

fn is_const(d: &Definition, e: ExprId, value: Value) -> bool {
    matches!(d.expr(e).kind, ExprKind::Const(v) if v == value)
}
