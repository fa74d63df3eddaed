//! Pass planning: which GPU passes a frame needs, and why. A scene simulates only what it calls
//! for (no shadow maps without a shadow-casting light and caster, no splat or gather without a
//! translucent object), and a frame recomputes only what its change invalidates: light or
//! geometry changes rerun shadows, splat and gather; a camera move reruns only shading (vertex
//! gather: exitance lives on the surface and does not depend on the view).

use std::fmt;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Pass {
    Shadow,
    Splat,
    Gather,
    Shade,
    Tonemap,
}

impl Pass {
    pub fn name(self) -> &'static str {
        match self {
            Pass::Shadow => "shadow",
            Pass::Splat => "splat",
            Pass::Gather => "gather",
            Pass::Shade => "shade",
            Pass::Tonemap => "tonemap",
        }
    }
}

/// What changed since the last frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Change {
    /// Nothing computed yet.
    Everything,
    /// A light moved or changed: visibility and irradiance are stale.
    Lights,
    /// Only the camera moved.
    Camera,
}

/// What a scene contains that decides its passes.
#[derive(Clone, Copy, Debug)]
pub struct SceneNeeds {
    pub shadow_layers: u32,
    pub translucent_objects: usize,
}

#[derive(Clone, Debug, Default)]
pub struct Plan {
    pub passes: Vec<(Pass, String)>,
    pub skipped: Vec<(Pass, String)>,
}

impl Plan {
    pub fn runs(&self, pass: Pass) -> bool {
        self.passes.iter().any(|(p, _)| *p == pass)
    }
}

impl fmt::Display for Plan {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (p, why) in &self.passes {
            writeln!(f, "  run  {:<8} {why}", p.name())?;
        }
        for (p, why) in &self.skipped {
            writeln!(f, "  skip {:<8} {why}", p.name())?;
        }
        Ok(())
    }
}

pub fn plan(needs: SceneNeeds, change: Change) -> Plan {
    let mut plan = Plan::default();
    let lights_stale = matches!(change, Change::Everything | Change::Lights);
    let mut add = |pass: Pass, run: bool, yes: &str, no: &str| {
        if run {
            plan.passes.push((pass, yes.to_string()));
        } else {
            plan.skipped.push((pass, no.to_string()));
        }
    };
    let has_shadows = needs.shadow_layers > 0;
    add(
        Pass::Shadow,
        has_shadows && lights_stale,
        "lights changed: shadow maps are stale",
        if has_shadows {
            "lights and geometry unchanged: shadow maps reused"
        } else {
            "no light casts a shadow onto a caster"
        },
    );
    let translucent = needs.translucent_objects > 0;
    add(
        Pass::Splat,
        translucent && lights_stale,
        "lights changed: irradiance at the samples is stale",
        if translucent { "lights unchanged: sample irradiance reused" } else { "no translucent object" },
    );
    add(
        Pass::Gather,
        translucent && lights_stale,
        "sample irradiance changed: exitance is stale",
        if translucent { "exitance is view-independent and unchanged: reused" } else { "no translucent object" },
    );
    add(Pass::Shade, true, "every frame draws the view", "");
    add(Pass::Tonemap, true, "every frame's HDR image is tone-mapped", "");
    plan
}
