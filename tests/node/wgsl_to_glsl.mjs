// wgsl_to_glsl.mjs IN.wgsl OUT.frag ENTRY -- translates a WGSL module with a fragment entry point to
// GLSL 3.30 with naga (wgpu's shader translator, naga-wasm pinned by package-lock.json), after
// naga's validation, so that the WGSL can be run on an OpenGL rasteriser (tests/test_gpu_ltc.c
// --wgsl).  Each texture/sampler pair becomes a sampler2D named _group_G_binding_B_fs after the
// texture's binding.  Exit 1 with naga's report on any error.
import { readFileSync, writeFileSync } from "node:fs";
import { NagaError, parseWgsl, validate, writeGlsl } from "naga-wasm";

const [input, output, entry] = process.argv.slice(2);
let module = null, info = null;
try {
  module = parseWgsl(readFileSync(input, "utf8"));
  info = validate(module);
  writeFileSync(output, writeGlsl(module, info, { version: "330", stage: "fragment", entryPoint: entry || "main" }));
} catch (e) {
  console.error(`${input}: ${e instanceof NagaError ? `${e.kind}: ${e.formatted || e.message}` : e}`);
  process.exit(1);
} finally {
  if (info) info.free();
  if (module) module.free();
}
