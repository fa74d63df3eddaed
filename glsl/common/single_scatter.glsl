// Single scattering of a homogeneous half-space behind a smooth dielectric boundary (Jensen et
// al. 2001, Eq. 3, after Hanrahan and Krueger 1993): the f32 twin of src/optics/single_scatter.rs,
// whose module doc derives the integral. tests/optics_gpu.rs compares the two.
//
// R1(mu_i) = albedo int_{mu_c}^1 int_0^{2 pi} p(cos psi) F_t(mu, 1/eta) mu / (mu_i + mu) dphi dmu,
// mu = mu_c + (1 - mu_c) s^2, 16-point Gauss-Legendre in s on [0, 1] and in phi on [0, pi].
// Needs dipole_fresnel_transmittance (include dipole.glsl first).

#ifndef SINGLE_SCATTER_GLSL
#define SINGLE_SCATTER_GLSL

const float SS_PI = 3.14159265358979;

// The positive half of the 16 Gauss-Legendre nodes on [-1, 1] and their weights (the rule is
// symmetric).
const float SS_GL_X[8] = float[8](0.0950125098376374, 0.2816035507792589, 0.4580167776572274,
    0.6178762444026438, 0.7554044083550030, 0.8656312023878318, 0.9445750230732326, 0.9894009349916499);
const float SS_GL_W[8] = float[8](0.1894506104550685, 0.1826034150449236, 0.1691565193950025,
    0.1495959888165768, 0.1246289712555340, 0.0951585116824929, 0.0622535239386478, 0.0271524594117541);

// Henyey-Greenstein phase function, normalised over the sphere.
float ss_henyey_greenstein(float cos_psi, float g) {
    float denom = 1.0 + g * g - 2.0 * g * cos_psi;
    return (1.0 - g * g) / (4.0 * SS_PI * denom * sqrt(denom));
}

// 2 int_0^pi p(-mu_i mu + sin_i sin_o cos phi) dphi: 2 pi / (4 pi) when g = 0.
float ss_azimuthal(float mu_i, float sin_i, float mu, float g) {
    if (g == 0.0) return 0.5;
    float sin_o = sqrt(max(1.0 - mu * mu, 0.0));
    float sum = 0.0;
    for (int k = 0; k < 16; ++k) {
        float y = k < 8 ? -SS_GL_X[7 - k] : SS_GL_X[k - 8];
        float v = k < 8 ? SS_GL_W[7 - k] : SS_GL_W[k - 8];
        float phi = 0.5 * SS_PI * (y + 1.0);
        sum += v * 0.5 * SS_PI * ss_henyey_greenstein(-mu_i * mu + sin_i * sin_o * cos(phi), g);
    }
    return 2.0 * sum;
}

// The squared cosine of the refracted direction inside (Snell's law; <= 0: nothing enters),
// formed without the cancellation of 1 - sin^2 at grazing incidence.
float ss_refracted_cosine_sq(float cos_out, float eta) {
    return (cos_out * cos_out + (eta - 1.0) * (eta + 1.0)) / (eta * eta);
}

// Of the flux entering through the plane at incidence cosine cos_out outside, the share that
// leaves after exactly one scattering (single_scatter::reflectance). 0 where nothing enters.
float single_scatter_reflectance(float albedo, float g, float eta, float cos_out) {
    if (!(cos_out > 0.0 && cos_out <= 1.0)) return 0.0;
    float cos_sq = ss_refracted_cosine_sq(cos_out, eta);
    if (cos_sq <= 0.0) return 0.0;
    float mu_i = sqrt(cos_sq);
    float sin_i = sqrt((1.0 - cos_out) * (1.0 + cos_out)) / eta;
    float mu_c = eta > 1.0 ? sqrt(1.0 - 1.0 / (eta * eta)) : 0.0;
    float sum = 0.0;
    for (int k = 0; k < 16; ++k) {
        float x = k < 8 ? -SS_GL_X[7 - k] : SS_GL_X[k - 8];
        float w = k < 8 ? SS_GL_W[7 - k] : SS_GL_W[k - 8];
        float s = 0.5 * (x + 1.0);
        float mu = mu_c + (1.0 - mu_c) * s * s;
        float jacobian = w * (1.0 - mu_c) * s;
        sum += jacobian * ss_azimuthal(mu_i, sin_i, mu, g) * dipole_fresnel_transmittance(mu, 1.0 / eta) * mu
            / (mu_i + mu);
    }
    return albedo * sum;
}

#endif
