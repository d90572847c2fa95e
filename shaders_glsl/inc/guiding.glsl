// Temporary stand-in for the SD-tree include (uniform sphere), replaced by the real one.
#ifndef INC_GUIDING_GLSL
#define INC_GUIDING_GLSL

uint guide_find_leaf(vec3 p) { return 0u; }

vec3 guide_sample(uint leaf, vec2 u, out float pdf) {
    float z = 1.0 - 2.0 * u.x;
    float r = sqrt(max(0.0, 1.0 - z * z));
    float phi = TWO_PI * u.y;
    pdf = INV_FOUR_PI;
    return vec3(r * cos(phi), r * sin(phi), z);
}

float guide_pdf(uint leaf, vec3 dir) { return INV_FOUR_PI; }

void guide_record(vec3 p, vec3 dir, float value, float statistical_weight, vec3 jitter) {}

#endif
