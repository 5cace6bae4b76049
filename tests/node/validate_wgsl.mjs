// validate_wgsl.mjs FILE.wgsl... -- each file through naga (wgpu's WGSL front end and IR validator,
// the naga-wasm package pinned by package-lock.json): parse, then validate every function of the
// module with naga's default validation flags and capabilities.  As a check that the validator is
// live, each file is also validated with one ill-typed function appended, which must be refused.
// Prints one line per file; exit 0 iff every file validates and every control is refused.
import { readFileSync } from "node:fs";
import { NagaError, nagaVersion, parseWgsl, validate } from "naga-wasm";

function check(source) {
  let module = null, info = null;
  try {
    module = parseWgsl(source);
    info = validate(module);
    return null;
  } catch (e) {
    return e instanceof NagaError ? `${e.kind}: ${e.formatted || e.message}` : String(e);
  } finally {
    if (info) info.free();
    if (module) module.free();
  }
}

const control = "\nfn mfkit_control_ill_typed(a: vec3<f32>) -> f32 { return a; }\n";
let failed = 0;
for (const path of process.argv.slice(2)) {
  const src = readFileSync(path, "utf8");
  const err = check(src);
  const ctl = check(src + control);
  if (err) {
    ++failed;
    console.log(`FAIL ${path}: naga ${nagaVersion} refuses it:\n${err}`);
  } else if (!ctl) {
    ++failed;
    console.log(`FAIL ${path}: the ill-typed control function was accepted (the validator is not checking)`);
  } else {
    console.log(`ok ${path}: naga ${nagaVersion} parses and validates it (${src.split("\n").length} lines; control refused)`);
  }
}
if (process.argv.length <= 2) {
  console.log("FAIL: no .wgsl file given");
  failed = 1;
}
process.exit(failed ? 1 : 0);
