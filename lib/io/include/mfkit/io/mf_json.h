/*
 * mf_json.h -- the one JSON emitter of mfkit (tables' metadata, fit sidecars, gate reports,
 * study outputs).  Appends to an mf_buf (mf_io.h).
 *
 * Rules (docs/tables.md, "JSON numbers"):
 *   - strings: '"' and '\\' escaped, control characters (< 0x20) and DEL as \n, \t or \u00XX;
 *     other bytes (UTF-8) as they are.
 *   - numbers: doubles "%.17g" (they read back bitwise), stored floats "%.9g" of the float.
 *   - non-finite values: JSON has no NaN or infinity, so they are written as the strings
 *     "NaN", "Infinity" and "-Infinity" (the spellings of JavaScript and Python).  Every mfkit
 *     reader accepts them where it accepts a number (mf_json_nonfinite), and so does a script:
 *     float("NaN") and Number("Infinity") work.
 */
#ifndef MF_JSON_H
#define MF_JSON_H

#include <mfkit/io/mf_io.h>
#include <mfkit/mf_check.h>

#ifdef __cplusplus
extern "C" {
#endif

/* A JSON string literal of the NUL-terminated s (NULL: null). */
void mf_json_string(mf_buf *b, const char *s);
/* A double: "%.17g", or "NaN" / "Infinity" / "-Infinity" (with the quotes). */
void mf_json_number(mf_buf *b, double v);
/* A stored float: "%.9g" (9 significant digits identify a float), "-0.0" for negative zero (some
 * parsers read "-0" as the integer 0), non-finite values as mf_json_number. */
void mf_json_float(mf_buf *b, float v);
/* true / false. */
void mf_json_bool(mf_buf *b, int v);
/* A report of n checks (mf_check.h), indented as the value of an object member at the top level:
 *   [
 *       {"name": ..., "what": ..., "worst": ..., "bound": ..., "passed": ..., "cases": ..., "worst_at": ...},
 *       ...
 *     ]
 * (four spaces before each check, two before the closing bracket; numbers as mf_json_number).
 * The one format of the check reports: mfkit validate --json and the LTC bake's gate report. */
void mf_json_checks(mf_buf *b, const mf_check *c, int n);
/* Non-zero, with *out set, if s is one of the strings mf_json_number writes for a non-finite value. */
int mf_json_nonfinite(const char *s, double *out);

#ifdef __cplusplus
}
#endif
#endif /* MF_JSON_H */
