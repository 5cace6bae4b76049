#!/usr/bin/env bash
# test_prefilter_lookup.sh MFKIT SRC LOOKUP -- `mfkit prefilter`'s textures and lookup snippets on a
# 16 x 8 cut of the shipped V-groove map (not square, so that a swapped width and height shows) with
# 2 x 2 views (about 2 s of CPU): the GLSL and HLSL snippets compile (glslangValidator, in a fragment
# shader each that calls both mfpfLookup and the split lookup mfpfLookupTap), and LOOKUP (test_prefilter_lookup.c, the C twin of the snippet over the EXR atlases)
# matches the .npy arrays.
mfkit="$1"; src="$2"; lookup="$3"
source "$(dirname "$0")/cli_test_lib.sh"
oiiotool "$src/tests/data/normalmaps/vgroove_16.png" --cut 16x8+0+4 -o "$tmp/map.png"
"$mfkit" prefilter "$tmp/map.png" --base ggx --views 2x2 --samples 256 --tile 4 --out "$tmp/pf" 2>"$tmp/pf.log"; rc=$?
ok '[ $rc -eq 0 ]' "prefilter of the 16 x 8 map exits 0 (rc=$rc): $(tail -2 "$tmp/pf.log")"

{ printf '#version 450\n'
  printf 'layout(binding = 0) uniform sampler2DArray t0;\nlayout(binding = 1) uniform sampler2DArray t1;\n'
  printf 'layout(binding = 2) uniform sampler2DArray t2;\n'
  printf 'layout(location = 0) in vec2 uv;\nlayout(location = 1) in vec3 view;\nlayout(location = 0) out vec4 color;\n'
  cat "$tmp/pf/prefilter_lookup.glsl"
  printf 'void main()\n{\n    mat3 M;\n    float magnitude;\n'
  printf '    mfpfLookup(t0, t1, t2, uv, view.z, view.x, view.y, M, magnitude);\n'
  printf '    color = vec4(magnitude * inverse(M)[2], 1.0);\n'
  printf '    for (int k = 0; k < 8; ++k) {\n        float w = mfpfLookupTap(t0, t1, t2, k, uv, view.z, view.x, view.y, M, magnitude);\n'
  printf '        if (w > 0.0) color.xyz += w * magnitude * inverse(M)[2];\n    }\n}\n'; } >"$tmp/lookup.frag"
glslangValidator -V -o "$tmp/glsl.spv" "$tmp/lookup.frag" >"$tmp/glsl.log" 2>&1; rc=$?
ok '[ $rc -eq 0 ]' "the GLSL lookup compiles (rc=$rc): $(head -c 800 "$tmp/glsl.log")"

{ printf 'Texture2DArray t0 : register(t0);\nTexture2DArray t1 : register(t1);\nTexture2DArray t2 : register(t2);\n'
  printf 'SamplerState s : register(s0);\n'
  cat "$tmp/pf/prefilter_lookup.hlsl"
  printf 'float4 main(float2 uv : TEXCOORD0, float3 view : TEXCOORD1) : SV_Target\n{\n    float3x3 M;\n    float magnitude;\n'
  printf '    mfpfLookup(t0, t1, t2, s, uv, view.z, view.x, view.y, M, magnitude);\n'
  printf '    float4 c = float4(magnitude * M[2], 1.0);\n'
  printf '    for (int k = 0; k < 8; ++k) {\n        float w = mfpfLookupTap(t0, t1, t2, k, uv, view.z, view.x, view.y, M, magnitude);\n'
  printf '        if (w > 0.0) c.xyz += w * magnitude * M[2];\n    }\n    return c;\n}\n'; } >"$tmp/lookup.hlsl"
glslangValidator -V -D -e main -S frag -o "$tmp/hlsl.spv" "$tmp/lookup.hlsl" >"$tmp/hlsl.log" 2>&1; rc=$?
ok '[ $rc -eq 0 ]' "the HLSL lookup compiles (rc=$rc): $(head -c 800 "$tmp/hlsl.log")"

"$lookup" "$tmp/pf" >"$tmp/twin.log" 2>&1; rc=$?
ok '[ $rc -eq 0 ]' "the C twin of the lookup matches the .npy arrays (rc=$rc): $(head -c 1500 "$tmp/twin.log")"
cat "$tmp/twin.log"
finish test_prefilter_lookup
