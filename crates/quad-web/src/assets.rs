//! The page's static files, embedded in the binary: the page itself from `web/`, the
//! WebAssembly kin-core and three.js as `build.rs` prepared them.

/// One embedded file: its URL path, content type and bytes.
pub struct Asset {
    /// URL path.
    pub path: &'static str,
    /// `Content-Type`.
    pub content_type: &'static str,
    /// The bytes.
    pub bytes: &'static [u8],
}

macro_rules! web {
    ($file:literal) => {
        include_bytes!(concat!(env!("CARGO_MANIFEST_DIR"), "/../../web/", $file))
    };
}

macro_rules! built {
    ($file:literal) => {
        include_bytes!(concat!(env!("OUT_DIR"), "/assets/", $file))
    };
}

const JS: &str = "text/javascript; charset=utf-8";

/// Every file the server serves besides the WebSocket.
pub const ASSETS: &[Asset] = &[
    Asset {
        path: "/",
        content_type: "text/html; charset=utf-8",
        bytes: web!("index.html"),
    },
    Asset {
        path: "/app.js",
        content_type: JS,
        bytes: web!("app.js"),
    },
    Asset {
        path: "/kin.js",
        content_type: JS,
        bytes: web!("kin.js"),
    },
    Asset {
        path: "/style.css",
        content_type: "text/css; charset=utf-8",
        bytes: web!("style.css"),
    },
    Asset {
        path: "/kin.wasm",
        content_type: "application/wasm",
        bytes: built!("kin.wasm"),
    },
    Asset {
        path: "/vendor/three.module.js",
        content_type: JS,
        bytes: built!("three.module.js"),
    },
    Asset {
        path: "/vendor/three.core.js",
        content_type: JS,
        bytes: built!("three.core.js"),
    },
    Asset {
        path: "/vendor/OrbitControls.js",
        content_type: JS,
        bytes: built!("OrbitControls.js"),
    },
];

/// The embedded file at `path`.
pub fn get(path: &str) -> Option<&'static Asset> {
    ASSETS.iter().find(|a| a.path == path)
}

/// A page the build could not complete (see `build.rs`): the server still serves it, and the
/// page says what is missing.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum Incomplete {
    /// `kin.wasm` was not built: no pose preview in the page.
    #[error(
        "kin.wasm was not built: run `rustup target add wasm32-unknown-unknown` \
         (scripts/install-deps.sh does) and rebuild"
    )]
    Wasm,
    /// three.js was not bundled: no 3D view in the page.
    #[error(
        "three.js was not bundled: run `npm ci` in web/ (scripts/install-deps.sh does) and rebuild"
    )]
    Three,
}

/// Whether the embedded page is complete: kin-core in WebAssembly and three.js both bundled.
///
/// # Errors
/// The first missing piece.
pub fn check() -> Result<(), Incomplete> {
    let missing = env!("QUAD_WEB_MISSING");
    if missing.split(' ').any(|m| m == "kin.wasm") {
        return Err(Incomplete::Wasm);
    }
    if missing.split(' ').any(|m| m == "three.js") {
        return Err(Incomplete::Three);
    }
    debug_assert!(built!("kin.wasm").starts_with(b"\0asm"));
    Ok(())
}

#[cfg(test)]
mod tests {
    /// The CI builds the whole page: the wasm target and `npm ci` come from install-deps.
    #[test]
    fn the_page_is_complete() {
        super::check().unwrap();
        let wasm = super::get("/kin.wasm").unwrap();
        assert!(wasm.bytes.starts_with(b"\0asm"), "kin.wasm is WebAssembly");
        let three = super::get("/vendor/three.module.js").unwrap();
        assert!(three.bytes.len() > 10_000, "three.js bundled");
    }
}
