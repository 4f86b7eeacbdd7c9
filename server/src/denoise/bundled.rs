//! OIDN's four trained networks, embedded in the binary from
//! `server/assets/weights/oidn/` (Apache-2.0; the README there has their
//! checksums and format). A scene's `[denoiser]` without `weights`, and
//! `loupe denoise` without `--weights`, run the one trained for the
//! colour's range that takes the inputs given: an installed loupe needs no
//! file beside it.

use super::network::{Inputs, Network};
use super::tza::Archive;
use crate::denoise_options::Mode;
use crate::diag::{Code, Diagnostic};

/// One embedded weights file.
pub struct Bundled {
    /// Its name in `server/assets/weights/oidn/`.
    pub name: &'static str,
    pub bytes: &'static [u8],
}

macro_rules! bundled {
    ($name:literal) => {
        Bundled { name: $name, bytes: include_bytes!(concat!("../../assets/weights/oidn/", $name)) }
    };
}

static HDR: Bundled = bundled!("rt_hdr.tza");
static HDR_ALB_NRM: Bundled = bundled!("rt_hdr_alb_nrm.tza");
static LDR: Bundled = bundled!("rt_ldr.tza");
static LDR_ALB_NRM: Bundled = bundled!("rt_ldr_alb_nrm.tza");

/// The bundled weights trained for `mode`'s range (`ldr_srgb` is LDR: the
/// network sees sRGB-encoded values either way) taking `inputs`; an
/// unlocated diagnostic (the caller knows what to point at) for colour and
/// albedo without a normal, a network loupe does not bundle.
pub fn weights(mode: Mode, inputs: Inputs) -> Result<&'static Bundled, Diagnostic> {
    match (mode, inputs) {
        (Mode::Hdr, Inputs::Color) => Ok(&HDR),
        (Mode::Hdr, Inputs::ColorAlbedoNormal) => Ok(&HDR_ALB_NRM),
        (Mode::Ldr | Mode::LdrSrgb, Inputs::Color) => Ok(&LDR),
        (Mode::Ldr | Mode::LdrSrgb, Inputs::ColorAlbedoNormal) => Ok(&LDR_ALB_NRM),
        (_, Inputs::ColorAlbedo) => Err(Diagnostic::error(
            Code::Weights,
            format!(
                "loupe bundles OIDN's networks for colour alone and for colour, albedo and normal; none takes {}: name a weights file (.tza) that does",
                inputs.describe()
            ),
        )),
    }
}

impl Bundled {
    /// How diagnostics name it.
    pub fn display(&self) -> String {
        format!("{} (bundled)", self.name)
    }

    /// The network these weights describe. The tests below build all four;
    /// a failure stays a diagnostic rather than a panic.
    pub fn network(&self) -> Result<Network, Diagnostic> {
        let display = self.display();
        let archive = Archive::parse(self.bytes.to_vec()).map_err(|e| e.diagnostic(&display))?;
        Network::from_archive(&archive).map_err(|e| e.diagnostic(&display))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use sha2::{Digest, Sha256};

    const MODES: [Mode; 3] = [Mode::Hdr, Mode::Ldr, Mode::LdrSrgb];

    /// The sha256 the README states for `name`, from the row that names it.
    fn stated_sha256(readme: &str, name: &str) -> String {
        let row =
            readme.lines().find(|l| l.starts_with(&format!("| `{name}`"))).unwrap_or_else(|| panic!("the README has no row for {name}"));
        let hex = row.split(['|', '`', ' ']).find(|w| w.len() == 64 && w.bytes().all(|b| b.is_ascii_hexdigit()));
        hex.unwrap_or_else(|| panic!("no sha256 in {row}")).to_owned()
    }

    #[test]
    fn the_embedded_bytes_are_the_files_the_readme_checksums() {
        let readme = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/assets/weights/oidn/README.md")).unwrap();
        for b in [&HDR, &HDR_ALB_NRM, &LDR, &LDR_ALB_NRM] {
            let sha: String = Sha256::digest(b.bytes).iter().map(|x| format!("{x:02x}")).collect();
            assert_eq!(sha, stated_sha256(&readme, b.name), "{}", b.name);
        }
    }

    #[test]
    fn each_range_and_inputs_get_a_network_that_takes_them() {
        for mode in MODES {
            for inputs in [Inputs::Color, Inputs::ColorAlbedoNormal] {
                let net = weights(mode, inputs).and_then(Bundled::network).unwrap_or_else(|d| panic!("{mode:?} {inputs:?}: {d}"));
                assert_eq!(net.inputs, inputs, "{mode:?}");
            }
        }
        let name = |mode, inputs| weights(mode, inputs).map(|b| b.name).ok();
        assert_eq!(name(Mode::Hdr, Inputs::Color), Some("rt_hdr.tza"));
        assert_eq!(name(Mode::Hdr, Inputs::ColorAlbedoNormal), Some("rt_hdr_alb_nrm.tza"));
        assert_eq!(name(Mode::Ldr, Inputs::Color), Some("rt_ldr.tza"));
        assert_eq!(name(Mode::LdrSrgb, Inputs::ColorAlbedoNormal), Some("rt_ldr_alb_nrm.tza"), "sRGB-encoded LDR is LDR");
    }

    #[test]
    fn colour_and_albedo_alone_have_no_bundled_network() {
        for mode in MODES {
            let d = weights(mode, Inputs::ColorAlbedo).err().expect("none is bundled");
            assert!(d.code == Code::Weights && d.message.contains("none takes colour and albedo"), "{d}");
        }
    }

    /// Every file under `dir` but build outputs and git's own.
    fn files(dir: &std::path::Path, out: &mut Vec<std::path::PathBuf>) {
        for e in std::fs::read_dir(dir).unwrap() {
            let path = e.unwrap().path();
            if path.is_dir() {
                if !path.ends_with("target") && !path.ends_with(".git") {
                    files(&path, out);
                }
            } else {
                out.push(path);
            }
        }
    }

    /// A clone has the weights it needs: nothing in the repository reads
    /// them from a folder beside it any more, as the tests once did.
    #[test]
    fn nothing_in_the_repository_reads_weights_from_beside_it() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
        let mut all = Vec::new();
        files(&root, &mut all);
        assert!(all.iter().any(|p| p.ends_with("rt_hdr_alb_nrm.tza")), "the walk sees the repository");
        // Spelled in two halves so that this file does not match itself.
        let beside = ["../sha", "red/"].concat();
        let found: Vec<_> =
            all.iter().filter(|p| std::fs::read(p).is_ok_and(|b| b.windows(beside.len()).any(|w| w == beside.as_bytes()))).collect();
        assert!(found.is_empty(), "these refer to {beside}: {found:?}");
    }
}
