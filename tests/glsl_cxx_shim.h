/* glsl_cxx_shim.h -- a C++ stand-in for the GLSL that mfkit's lookup snippets use, so the twin
 * tests (test_table_nd, test_ltc_aniso_shader) compile a generated snippet as C++ and compare its
 * arithmetic with the C library: scalar math, vec2/vec3/vec4 with components, mat3 from 9 floats in
 * column order with m[column], and textureLod as the bilinear filter with clamp-to-edge of a texture
 * whose texel centres are at (i + 0.5)/n.  -DTWIN_DOUBLE evaluates everything in double. */
#ifndef MF_GLSL_CXX_SHIM_H
#define MF_GLSL_CXX_SHIM_H

static const char k_glsl_cxx_shim[] =
    "#include <cmath>\n#include <cstdio>\n#include <cstdlib>\n#include <vector>\n"
    "#ifdef TWIN_DOUBLE\n#define float double\n#endif\n"
    "struct vec2 { float x, y; vec2(float a, float b) : x(a), y(b) {} };\n"
    "struct vec3 { float x, y, z; vec3() : x(0), y(0), z(0) {} vec3(float a, float b, float c) : x(a), y(b), z(c) {} };\n"
    "struct vec4 { float x, y, z, w;\n"
    "  explicit vec4(float a) : x(a), y(a), z(a), w(a) {}\n"
    "  vec4 &operator+=(const vec4 &o) { x += o.x; y += o.y; z += o.z; w += o.w; return *this; } };\n"
    "static vec4 operator*(float s, vec4 a) { a.x = s * a.x; a.y = s * a.y; a.z = s * a.z; a.w = s * a.w; return a; }\n"
    "struct mat3 { vec3 c[3]; mat3() {}\n"
    "  mat3(float a, float b, float d, float e, float f, float g, float h, float i, float j)\n"
    "  { c[0] = vec3(a, b, d); c[1] = vec3(e, f, g); c[2] = vec3(h, i, j); }\n"
    "  const vec3 &operator[](int k) const { return c[k]; } };\n"
    "static float clamp(float x, float a, float b) { return std::fmin(std::fmax(x, a), b); }\n"
    "static float max(float a, float b) { return std::fmax(a, b); }\n"
    "static int min(int a, int b) { return a < b ? a : b; }\n"
    "static float atan(float y, float x) { return std::atan2(y, x); }\n"
    "using std::floor; using std::sqrt; using std::acos;\n"
    "struct texture { int w, h; std::vector<float> t; };\n"
    "typedef const texture &sampler2D;\n"
    "static vec4 textureLod(sampler2D s, vec2 uv, float) {\n"
    "  float xf = uv.x * float(s.w) - 0.5, yf = uv.y * float(s.h) - 0.5;\n"
    "  float x0 = floor(xf), y0 = floor(yf), fx = xf - x0, fy = yf - y0;\n"
    "  vec4 r(0.0);\n"
    "  for (int c = 0; c < 4; ++c) {\n"
    "    int dx = c & 1, dy = c >> 1;\n"
    "    float w = (dx ? fx : 1.0 - fx) * (dy ? fy : 1.0 - fy);\n"
    "    int x = int(x0) + dx, y = int(y0) + dy;\n"
    "    x = x < 0 ? 0 : (x >= s.w ? s.w - 1 : x); y = y < 0 ? 0 : (y >= s.h ? s.h - 1 : y);\n"
    "    const float *p = &s.t[(size_t(y) * size_t(s.w) + size_t(x)) * 4];\n"
    "    r.x += w * p[0]; r.y += w * p[1]; r.z += w * p[2]; r.w += w * p[3];\n"
    "  }\n"
    "  return r;\n"
    "}\n";

#endif /* MF_GLSL_CXX_SHIM_H */
