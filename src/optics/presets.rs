//! Measured materials: plain static data.
//!
//! Provenance:
//! - [`JENSEN_2001`]: Jensen, Marschner, Levoy, Hanrahan, "A Practical Model for Subsurface Light
//!   Transport", SIGGRAPH 2001, the table of measured parameters: `sigma_s'` and `sigma_a` in 1/mm
//!   for R, G, B; eta 1.3, except marble 1.5 (as docs/optics.md, "Measured materials", gives them).
//! - [`NARASIMHAN_2006`]: Narasimhan, Gupta, Donner, Ramamoorthi, Nayar, Jensen, "Acquiring
//!   Scattering Properties of Participating Media by Dilution", SIGGRAPH 2006, in 1/mm, as pbrt-v3
//!   lists them (src/core/medium.cpp), in the same `sigma_s'` column as Jensen's values; we use
//!   them as `sigma_s'` too. No boundary index comes with them; 1.33 (water, the medium of the
//!   dilutions) is assumed here.
//!
//! The numbers were transcribed from pbrt-v3's table and checked entry by entry.

use super::{Material, OpticsError};

/// Which measurement a preset comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum Source {
    /// Jensen et al. 2001, "A Practical Model for Subsurface Light Transport".
    Jensen2001,
    /// Narasimhan et al. 2006, "Acquiring Scattering Properties of Participating Media by Dilution".
    Narasimhan2006,
}

impl Source {
    /// A short citation for listings.
    pub fn citation(self) -> &'static str {
        match self {
            Source::Jensen2001 => "Jensen et al. 2001",
            Source::Narasimhan2006 => "Narasimhan et al. 2006",
        }
    }
}

/// One measured material: coefficients in 1/mm per channel (R, G, B).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct MeasuredMaterial {
    /// The name as published (matched by [`find`] ignoring case, spaces and punctuation).
    pub name: &'static str,
    /// Reduced scattering coefficient `sigma_s'` (1/mm).
    pub sigma_s_prime: [f64; 3],
    /// Absorption coefficient `sigma_a` (1/mm).
    pub sigma_a: [f64; 3],
    /// Relative index of refraction.
    pub eta: f64,
    /// Which measurement it comes from.
    pub source: Source,
}

impl MeasuredMaterial {
    /// The preset as a [`Material`]. The table holds only valid values (a test checks it).
    pub fn material(&self) -> Material {
        Material {
            name: self.name.to_string(),
            sigma_a: self.sigma_a,
            sigma_s_prime: self.sigma_s_prime,
            eta: self.eta,
        }
    }
}

const fn jensen(name: &'static str, sigma_s_prime: [f64; 3], sigma_a: [f64; 3], eta: f64) -> MeasuredMaterial {
    MeasuredMaterial { name, sigma_s_prime, sigma_a, eta, source: Source::Jensen2001 }
}

const fn dilution(name: &'static str, sigma_s_prime: [f64; 3], sigma_a: [f64; 3]) -> MeasuredMaterial {
    MeasuredMaterial { name, sigma_s_prime, sigma_a, eta: 1.33, source: Source::Narasimhan2006 }
}

/// The 12 materials measured by Jensen et al. 2001: (name, sigma_s', sigma_a, eta).
#[rustfmt::skip]
pub static JENSEN_2001: [MeasuredMaterial; 12] = [
    jensen("Apple",      [2.29, 2.39, 1.97],  [0.0030, 0.0034, 0.046],   1.3),
    jensen("Chicken1",   [0.15, 0.21, 0.38],  [0.015, 0.077, 0.19],      1.3),
    jensen("Chicken2",   [0.19, 0.25, 0.32],  [0.018, 0.088, 0.20],      1.3),
    jensen("Cream",      [7.38, 5.47, 3.15],  [0.0002, 0.0028, 0.0163],  1.3),
    jensen("Ketchup",    [0.18, 0.07, 0.03],  [0.061, 0.97, 1.45],       1.3),
    jensen("Marble",     [2.19, 2.62, 3.00],  [0.0021, 0.0041, 0.0071],  1.5),
    jensen("Potato",     [0.68, 0.70, 0.55],  [0.0024, 0.0090, 0.12],    1.3),
    jensen("Skimmilk",   [0.70, 1.22, 1.90],  [0.0014, 0.0025, 0.0142],  1.3),
    jensen("Skin1",      [0.74, 0.88, 1.01],  [0.032, 0.17, 0.48],       1.3),
    jensen("Skin2",      [1.09, 1.59, 1.79],  [0.013, 0.070, 0.145],     1.3),
    jensen("Spectralon", [11.6, 20.4, 14.9],  [0.00, 0.00, 0.00],        1.3),
    jensen("Wholemilk",  [2.55, 3.21, 3.77],  [0.0011, 0.0024, 0.014],   1.3),
];

/// The dilution measurements of Narasimhan et al. 2006: (name, sigma_s', sigma_a); eta 1.33.
#[rustfmt::skip]
pub static NARASIMHAN_2006: [MeasuredMaterial; 35] = [
    dilution("Lowfat Milk",                 [0.89187, 1.5136, 2.532],                [0.002875, 0.00575, 0.0115]),
    dilution("Reduced Milk",                [2.4858, 3.1669, 4.5214],                [0.0025556, 0.0051111, 0.012778]),
    dilution("Regular Milk",                [4.5513, 5.8294, 7.136],                 [0.0015333, 0.0046, 0.019933]),
    dilution("Espresso",                    [0.72378, 0.84557, 1.0247],              [4.7984, 6.5751, 8.8493]),
    dilution("Mint Mocha Coffee",           [0.31602, 0.38538, 0.48131],             [3.772, 5.8228, 7.82]),
    dilution("Lowfat Soy Milk",             [0.30576, 0.34233, 0.61664],             [0.0014375, 0.0071875, 0.035937]),
    dilution("Regular Soy Milk",            [0.59223, 0.73866, 1.4693],              [0.0019167, 0.0095833, 0.065167]),
    dilution("Lowfat Chocolate Milk",       [0.64925, 0.83916, 1.1057],              [0.0115, 0.0368, 0.1564]),
    dilution("Regular Chocolate Milk",      [1.4585, 2.1289, 2.9527],                [0.010063, 0.043125, 0.14375]),
    dilution("Coke",                        [8.9053e-05, 8.372e-05, 0.0],            [0.10014, 0.16503, 0.2468]),
    dilution("Pepsi",                       [6.1697e-05, 4.2564e-05, 0.0],           [0.091641, 0.14158, 0.20729]),
    dilution("Sprite",                      [6.0306e-06, 6.4139e-06, 6.5504e-06],    [0.001886, 0.0018308, 0.0020025]),
    dilution("Gatorade",                    [0.0024574, 0.003007, 0.0037325],        [0.024794, 0.019289, 0.008878]),
    dilution("Chardonnay",                  [1.7982e-05, 1.3758e-05, 1.2023e-05],    [0.010782, 0.011855, 0.023997]),
    dilution("White Zinfandel",             [1.7501e-05, 1.9069e-05, 1.288e-05],     [0.012072, 0.016184, 0.019843]),
    dilution("Merlot",                      [2.1129e-05, 0.0, 0.0],                  [0.11632, 0.25191, 0.29434]),
    dilution("Budweiser Beer",              [2.4356e-05, 2.4079e-05, 1.0564e-05],    [0.011492, 0.024911, 0.057786]),
    dilution("Coors Light Beer",            [5.0922e-05, 4.301e-05, 0.0],            [0.006164, 0.013984, 0.034983]),
    dilution("Clorox",                      [0.0024035, 0.0031373, 0.003991],        [0.0033542, 0.014892, 0.026297]),
    dilution("Apple Juice",                 [0.00013612, 0.00015836, 0.000227],      [0.012957, 0.023741, 0.052184]),
    dilution("Cranberry Juice",             [0.00010402, 0.00011646, 7.8139e-05],    [0.039437, 0.094223, 0.12426]),
    dilution("Grape Juice",                 [5.382e-05, 0.0, 0.0],                   [0.10404, 0.23958, 0.29325]),
    dilution("Ruby Grapefruit Juice",       [0.011002, 0.010927, 0.011036],          [0.085867, 0.18314, 0.25262]),
    dilution("White Grapefruit Juice",      [0.22826, 0.23998, 0.32748],             [0.0138, 0.018831, 0.056781]),
    dilution("Shampoo",                     [0.0007176, 0.0008303, 0.0009016],       [0.014107, 0.045693, 0.061717]),
    dilution("Strawberry Shampoo",          [0.00015671, 0.00015947, 1.518e-05],     [0.01449, 0.05796, 0.075823]),
    dilution("Head & Shoulders Shampoo",    [0.023805, 0.028804, 0.034306],          [0.084621, 0.15688, 0.20365]),
    dilution("Lemon Tea Powder",            [0.040224, 0.045264, 0.051081],          [2.4288, 4.5757, 7.2127]),
    dilution("Orange Powder",               [0.00015617, 0.00017482, 0.0001762],     [0.001449, 0.003441, 0.007863]),
    dilution("Pink Lemonade Powder",        [0.00012103, 0.00013073, 0.00012528],    [0.001165, 0.002366, 0.003195]),
    dilution("Cappuccino Powder",           [1.8436, 2.5851, 2.1662],                [35.844, 49.547, 61.084]),
    dilution("Salt Powder",                 [0.027333, 0.032451, 0.031979],          [0.28415, 0.3257, 0.34148]),
    dilution("Sugar Powder",                [0.00022272, 0.00025513, 0.000271],      [0.012638, 0.031051, 0.050124]),
    dilution("Suisse Mocha Powder",         [2.7979, 3.5452, 4.3365],                [17.502, 27.004, 35.433]),
    dilution("Pacific Ocean Surface Water", [0.0001764, 0.00032095, 0.00019617],     [0.031845, 0.031324, 0.030147]),
];

/// Every preset, Jensen et al. first.
pub fn all() -> impl Iterator<Item = &'static MeasuredMaterial> {
    JENSEN_2001.iter().chain(NARASIMHAN_2006.iter())
}

/// The key names are compared by: lower case, letters and digits only, so that `marble`,
/// `MARBLE`, `lowfat milk`, `Lowfat-Milk` and `lowfat_milk` all match.
pub fn name_key(name: &str) -> String {
    name.chars().filter(|c| c.is_alphanumeric()).flat_map(char::to_lowercase).collect()
}

/// The preset with this name, compared case-insensitively (and ignoring spaces and punctuation).
pub fn find(name: &str) -> Result<&'static MeasuredMaterial, OpticsError> {
    let key = name_key(name);
    all()
        .find(|m| !key.is_empty() && name_key(m.name) == key)
        .ok_or_else(|| OpticsError::UnknownPreset(name.to_string()))
}
