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
