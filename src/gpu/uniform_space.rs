//! Where shaders read their parameter blocks from: uniform buffers, or —
//! on the one driver where that leaks — read-only storage buffers with the
//! same layout.
//!
//! Lavapipe before Mesa 23 specialises a shader for the values of the
//! uniforms its branches and loops test ("inlined uniforms") each time a
//! pipeline using it is bound, and never frees the variant or caches it:
//! every frame compiled and kept new machine code (about 2 MB a frame for
//! the shadow-map lookup), so memory grew and frames slowed without end.
//! Storage-buffer reads are never inlined. WGSL lays out a struct the same
//! way in both address spaces (the uniform space only adds checks), so the
//! buffers' bytes and the offsets are unchanged.

use std::borrow::Cow;

/// The address space of the shaders' `var<uniform>` blocks on a device.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum UniformSpace {
    /// Uniform buffers, as declared (every driver but the one below).
    Uniform,
    /// Read-only storage buffers (lavapipe of Mesa 22 and older).
    Storage,
}

impl UniformSpace {
    /// The space for an adapter: `Storage` on lavapipe (llvmpipe) whose
    /// Mesa version is below 23, else `Uniform`.
    pub fn for_adapter(info: &wgpu::AdapterInfo) -> UniformSpace {
        Self::for_driver(&info.name, &info.driver, &info.driver_info)
    }

    /// [`Self::for_adapter`] from the adapter's name, driver name and driver
    /// description.
    fn for_driver(name: &str, driver: &str, driver_info: &str) -> UniformSpace {
        let lavapipe = driver.eq_ignore_ascii_case("llvmpipe") || name.starts_with("llvmpipe");
        match mesa_major(driver_info) {
            Some(major) if lavapipe && major < 23 => UniformSpace::Storage,
            _ => UniformSpace::Uniform,
        }
    }

    /// The binding type of a parameter block.
    pub fn binding_type(self, has_dynamic_offset: bool) -> wgpu::BindingType {
        let ty = match self {
            UniformSpace::Uniform => wgpu::BufferBindingType::Uniform,
            UniformSpace::Storage => wgpu::BufferBindingType::Storage { read_only: true },
        };
        wgpu::BindingType::Buffer {
            ty,
            has_dynamic_offset,
            min_binding_size: None,
        }
    }

    /// The usage a parameter block's buffer needs (with `COPY_DST` to be
    /// written).
    pub fn usage(self) -> wgpu::BufferUsages {
        match self {
            UniformSpace::Uniform => wgpu::BufferUsages::UNIFORM,
            UniformSpace::Storage => wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::STORAGE,
        }
    }

    /// WGSL source with its `var<uniform>` declarations in this space.
    pub fn wgsl(self, source: &str) -> Cow<'_, str> {
        match self {
            UniformSpace::Uniform => Cow::Borrowed(source),
            UniformSpace::Storage => {
                Cow::Owned(source.replace("var<uniform>", "var<storage, read>"))
            }
        }
    }
}

/// The major version in a driver description such as "Mesa 22.3.6".
fn mesa_major(driver_info: &str) -> Option<u32> {
    let rest = &driver_info[driver_info.find("Mesa ")? + 5..];
    rest.split(|c: char| !c.is_ascii_digit())
        .next()?
        .parse()
        .ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_old_lavapipe_reads_parameter_blocks_from_storage() {
        let space = UniformSpace::for_driver;
        let old = space(
            "llvmpipe (LLVM 15.0.6, 256 bits)",
            "llvmpipe",
            "Mesa 22.3.6 (LLVM 15.0.6)",
        );
        let new = space(
            "llvmpipe (LLVM 19.1.7, 256 bits)",
            "llvmpipe",
            "Mesa 25.0.7-2 (LLVM 19.1.7)",
        );
        let gpu = space("AMD Radeon RX 7600 (RADV NAVI33)", "radv", "Mesa 22.3.6");
        assert_eq!(old, UniformSpace::Storage);
        assert_eq!(new, UniformSpace::Uniform);
        assert_eq!(gpu, UniformSpace::Uniform);
        assert_eq!(
            UniformSpace::Storage.wgsl("@group(0) @binding(0) var<uniform> frame: Frame;"),
            "@group(0) @binding(0) var<storage, read> frame: Frame;"
        );
        assert_eq!(mesa_major("Mesa 9.1"), Some(9));
        assert_eq!(mesa_major("NVIDIA 550.54"), None);
    }
}
