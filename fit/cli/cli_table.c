/*
 * cli_table.c -- `mfkit table convert IN OUT` and `mfkit table info FILE`: table files between
 * the formats of mf_table_io.h (docs/tables.md, docs/cli.md); `mfkit table plot TABLE` (heat maps of
 * every field) and `mfkit table lobe TABLE` (an LTC table's lobe beside its BRDF): the numbers from
 * the library, written as CSV, drawn by the plotting module (cli_plot.h).
 * Exit code 0 on success, 2 for a usage error, 3 for an I/O or format error; errors are one line
 * on stderr, and a failed convert leaves no output file (the writers are atomic).
 */
#include "cli.h"
#include "cli_opt.h"
#include "cli_plot.h"
#include "cli_util.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "mfkit/mfkit.h"

#include "mfkit/mf_table.h"
#include "mfkit/mf_table_kind.h"
#include "mfkit/io/mf_table_io.h"

static const char *const k_cmd = "table";

enum { T_HALF, T_DDS_FIELDS, T_PREFIX, T_NOPTS };
static const cli_opt k_convert_opts[T_NOPTS] = {
    {.name = "--half", .kind = CLI_OPT_FLAG, .help = "store half floats (.exr, .dds); prints the conversion error"},
    {.name = "--dds-fields", .metavar = "LIST", .kind = CLI_OPT_STRING,
     .help = "the fields of the R,G,B,A channels of a .dds, names or '-' for a channel of zeros (default: the first "
             "4 fields)"},
    {.name = "--prefix", .metavar = "NAME", .kind = CLI_OPT_STRING,
     .help = "identifier prefix of .h/.glsl/.hlsl (default: OUT's file name)"},
};
static const cli_command k_convert_cmd = {
    .name = "table convert",
    .synopsis = "IN OUT",
    .min_pos = 2,
    .max_pos = 2,
    .description = "Lookup-table files (docs/tables.md), the format from the extension:\n"
                   "  read and write  .exr (OpenEXR, float32 or half)  .dds (RGBA32F/RGBA16F + FILE.json sidecar)\n"
                   "                  .json (metadata + data)          .npy (NumPy + FILE.json sidecar)\n"
                   "  write only      .h (C header)  .glsl .hlsl (lookup snippets)  .csv\n",
    .opts = k_convert_opts,
    .nopts = T_NOPTS,
    .epilog = NULL,
};
static const cli_command k_info_cmd = {
    .name = "table info",
    .synopsis = "FILE",
    .min_pos = 1,
    .max_pos = 1,
    .description = "Prints the table's kind (mf_table_kind.h: its layout and the checks of its gate), the axes\n"
                   "(parameterisation, texel centres), the record layout, each field's range and NaN count, and\n"
                   "the metadata.\n",
    .opts = NULL,
    .nopts = 0,
    .epilog = "exit status: 0 success, 2 usage error, 3 I/O or format error\n",
};

enum { P_OUT, P_NO_PLOTS, P_NOPTS };
static const cli_opt k_plot_opts[P_NOPTS] = {
    {.name = "--out", .metavar = "DIR", .kind = CLI_OPT_STRING, .required = 1,
     .help = "the output directory (created if missing)"},
    {.name = "--no-plots", .kind = CLI_OPT_FLAG, .help = "the CSV file only (no python3 needed)"},
};
static const cli_command k_plot_cmd = {
    .name = "table plot",
    .synopsis = "TABLE",
    .min_pos = 1,
    .max_pos = 1,
    .description = "Heat maps of every field of TABLE (any table 'mfkit validate' reads, P_1.dds+P_2.dds for a pair)\n"
                   "over its first two axes in physical units (for more axes: the slice through the middle texel of\n"
                   "each further axis), each with a colour bar, and the table's gate verdict (its \"validated\"\n"
                   "metadata) in the title.  Writes DIR/<name>_fields.csv (every texel: indices, parameters,\n"
                   "physical values, fields, %.17g) and DIR/<name>_<field>.png, <name> the table file's stem.\n"
                   "The PNGs need /usr/bin/python3 (or $MFKIT_PYTHON) with numpy and matplotlib.\n",
    .opts = k_plot_opts,
    .nopts = P_NOPTS,
    .epilog = "exit status: 0 success, 2 usage error (also: python3 or matplotlib missing), 3 I/O or format error\n",
};

/* --at R,U */
static int parse_at(const char *arg, cli_val *v)
{
    char buf[128];
    const char *comma = strchr(arg, ',');
    if (!comma || strlen(arg) >= sizeof buf)
        return -1;
    memcpy(buf, arg, (size_t)(comma - arg));
    buf[comma - arg] = '\0';
    double r, u;
    if (cli_parse_double(buf, &r) != 0 || cli_parse_double(comma + 1, &u) != 0 || !isfinite(r) || !isfinite(u))
        return -1;
    v->lo = r;
    v->hi = u;
    return 0;
}

enum { L_AT, L_ALPHA, L_THETA, L_BRDF, L_POINTS, L_OUT, L_NO_PLOTS, L_NOPTS };
static const cli_opt k_lobe_opts[L_NOPTS] = {
    {.name = "--at", .metavar = "R,U", .kind = CLI_OPT_CUSTOM, .parse = parse_at,
     .expect = "two numbers R,U (the table's coordinates r and u, within its ranges)",
     .help = "the point, in the table's coordinates: r (alpha = r^2) and u (cos theta_o = 1 - u^2); between texels the "
             "table is interpolated as a shader does"},
    {.name = "--alpha", .metavar = "A", .kind = CLI_OPT_DOUBLE, .dlo = 0.0, .dhi = 1.0, .lo_open = 1,
     .help = "the point by physical values (with --theta): GGX-style roughness alpha"},
    {.name = "--theta", .metavar = "DEG", .kind = CLI_OPT_DOUBLE, .dlo = 0.0, .dhi = 89.9,
     .help = "the view zenith angle theta_o in degrees (with --alpha)"},
    {.name = "--brdf", .metavar = "NAME", .kind = CLI_OPT_STRING,
     .help = "the BRDF the table approximates (default: the table's \"brdf\" metadata)"},
    {.name = "--points", .metavar = "N", .kind = CLI_OPT_INT, .lo = 9, .hi = 100001, .def = "361",
     .help = "points per slice, over -90..90 degrees"},
    {.name = "--out", .metavar = "DIR", .kind = CLI_OPT_STRING, .required = 1,
     .help = "the output directory (created if missing)"},
    {.name = "--no-plots", .kind = CLI_OPT_FLAG, .help = "the CSV file only (no python3 needed)"},
};
static const cli_command k_lobe_cmd = {
    .name = "table lobe",
    .synopsis = "TABLE",
    .min_pos = 1,
    .max_pos = 1,
    .description =
        "The fitted lobe of an LTC table (ltc_isotropic) at one point beside the BRDF it approximates, both\n"
        "cosine-weighted (per steradian): magnitude * D_LTC(wi) against f(wo, wi) cos theta_i, in the view frame\n"
        "(wo in the +x half of the xz plane).  Two slices: the incidence plane, wi = (sin s, 0, cos s), and the\n"
        "plane perpendicular to it through the mirror direction wr = (-sin theta_o, 0, cos theta_o),\n"
        "wi = cos s wr + sin s (0, 1, 0); s over -90..90 degrees.  Writes DIR/lobe.csv (slice, s_deg, wi_x,\n"
        "wi_y, wi_z, ltc, brdf; %.17g) and DIR/lobe.png (both slices and a polar plot of the incidence plane).\n",
    .opts = k_lobe_opts,
    .nopts = L_NOPTS,
    .epilog = "exit status: 0 success, 2 usage error (also: python3 or matplotlib missing), 3 I/O or format error\n",
};

static void usage(FILE *f)
{
    cli_opt_usage(&k_convert_cmd, f);
    fputc('\n', f);
    cli_opt_usage(&k_info_cmd, f);
    fputc('\n', f);
    cli_opt_usage(&k_plot_cmd, f);
    fputc('\n', f);
    cli_opt_usage(&k_lobe_cmd, f);
}

/* Exit code of a failed read or write (cli_exit_code: 2 for what the user asked, 3 else). */
static int fail(mf_status st, const char *msg)
{
    cli_error(k_cmd, "%s", msg);
    return cli_exit_code(st);
}

/* "-", a field name: parses up to 4 comma-separated entries into ch (-1 = zeros). */
static int parse_dds_fields(const mf_table *t, const char *list, int ch[4])
{
    for (int c = 0; c < 4; ++c)
        ch[c] = -1;
    char buf[4 * 40];
    if (strlen(list) >= sizeof buf)
        return cli_error(k_cmd, "--dds-fields: list too long");
    strcpy(buf, list);
    int c = 0;
    char *save = buf;
    for (char *tok = buf;; tok = save) {
        char *comma = strchr(tok, ',');
        if (comma)
            *comma = '\0';
        save = comma ? comma + 1 : NULL;
        if (c >= 4)
            return cli_error(k_cmd, "--dds-fields: more than 4 channels");
        if (strcmp(tok, "-") != 0) {
            ch[c] = mf_table_field(t, tok);
            if (ch[c] < 0) {
                char names[MF_TABLE_MAX_FIELDS * (MF_TABLE_NAME_LEN + 2)] = "";
                for (int f = 0; f < t->nfields; ++f) {
                    if (f)
                        strcat(names, ", ");
                    strcat(names, t->fields[f]);
                }
                return cli_error(k_cmd, "--dds-fields: no field '%s' in the table (fields: %s)", tok, names);
            }
        }
        ++c;
        if (!save)
            break;
    }
    return 0;
}

static void print_half_error(cli_buf *b, const mf_table *t, const mf_half_error *e, int have_where)
{
    cli_buf_printf(b, "half-float conversion error: max abs %.3g, max rel %.3g", e->max_abs_error, e->max_rel_error);
    if (have_where && e->max_rel_error > 0) {
        size_t texel = e->worst_rel_index / (size_t)t->nfields;
        int f = (int)(e->worst_rel_index % (size_t)t->nfields);
        cli_buf_printf(b, " (field %s at texel (", t->fields[f]);
        for (int k = 0; k < t->naxes; ++k) {
            cli_buf_printf(b, "%s%zu", k ? ", " : "", texel % (size_t)t->axes[k].size);
            texel /= (size_t)t->axes[k].size;
        }
        cli_buf_printf(b, "))");
    }
    cli_buf_printf(b, "; %zu overflowed to infinity, %zu flushed to zero", e->overflow_count, e->underflow_count);
    if (have_where)
        cli_buf_printf(b, ", %zu half subnormals", e->subnormal_count);
    cli_buf_printf(b, "\n");
}

static int table_convert(int argc, char **argv)
{
    cli_val v[T_NOPTS];
    const char *pos[2];
    int npos;
    int prc = cli_opt_parse(&k_convert_cmd, argc - 1, argv + 1, ~0u, NULL, v, pos, &npos);
    if (prc == CLI_PARSE_HELP) {
        usage(stdout);
        return 0;
    }
    if (prc)
        return prc;
    const char *in = pos[0], *out = pos[1];
    const char *dds = v[T_DDS_FIELDS].set ? v[T_DDS_FIELDS].s : NULL, *prefix = v[T_PREFIX].set ? v[T_PREFIX].s : NULL;
    int half = v[T_HALF].set;
    mf_table_format fin = mf_table_format_from_path(in), fout = mf_table_format_from_path(out);
    if (!mf_table_format_readable(fin))
        return cli_error(k_cmd, "%s: cannot read %s files (readable: .exr .dds .json .npy)", in,
                         fin == MF_TABLE_FORMAT_UNKNOWN ? "these" : mf_table_format_name(fin));
    if (fout == MF_TABLE_FORMAT_UNKNOWN)
        return cli_error(k_cmd, "%s: unknown output format (.exr .dds .h .glsl .hlsl .json .npy .csv)", out);
    if (half && fout != MF_TABLE_FORMAT_EXR && fout != MF_TABLE_FORMAT_DDS)
        return cli_error(k_cmd, "--half: only .exr and .dds store half floats, not .%s", mf_table_format_name(fout));
    if (dds && fout != MF_TABLE_FORMAT_DDS)
        return cli_error(k_cmd, "--dds-fields: the output is not a .dds file");
    if (prefix && fout != MF_TABLE_FORMAT_C_HEADER && fout != MF_TABLE_FORMAT_GLSL && fout != MF_TABLE_FORMAT_HLSL)
        return cli_error(k_cmd, "--prefix: the output is not a .h, .glsl or .hlsl file");

    mf_table t;
    char msg[1024];
    mf_status st = mf_table_read(in, &t, NULL, msg, sizeof msg);
    if (st != MF_OK) {
        return fail(st, msg);
    }
    mf_table_write_options o;
    mf_table_write_options_default(&o);
    o.half_float = half;
    o.prefix = prefix;
    if (dds) {
        int rc = parse_dds_fields(&t, dds, o.dds_fields);
        if (rc) {
            mf_table_free(&t);
            return rc;
        }
        o.dds_fields_set = 1;
    }
    mf_half_error he;
    st = mf_table_write(out, &t, &o, &he, msg, sizeof msg);
    if (st != MF_OK) {
        mf_table_free(&t);
        return fail(st, msg);
    }
    cli_buf b = {0};
    cli_buf_printf(&b, "%s: %s, %zu texels x %d fields%s\n", out, mf_table_format_name(fout), mf_table_texels(&t),
                   t.nfields, half ? ", half floats" : "");
    if (half)
        print_half_error(&b, &t, &he, 1);
    mf_table_free(&t);
    int rc = cli_buf_write(&b, stdout) == 0 ? 0 : (cli_error(k_cmd, "stdout: write failed"), 3);
    cli_buf_free(&b);
    return rc;
}

/* "kind: NAME -- description; axes ...; fields ...; gate: checks" or why there is none
 * (mf_table_kind.h). */
static void describe_kind(cli_buf *b, const mf_table *t)
{
    char why[256];
    const mf_table_kind *k = mf_table_kind_of(t, why, sizeof why);
    if (!k) {
        cli_buf_printf(b, "kind: none (%s); 'mfkit validate' has no gate for it\n", why);
        return;
    }
    cli_buf_printf(b, "kind: %s -- %s (%s)\n", k->name, k->description,
                   mf_table_get_meta(t, "kind") ? "from the \"kind\" metadata" : "recognised by its layout");
    cli_buf_printf(b, "kind layout: %d axes (", k->naxes);
    for (int a = 0; a < k->naxes; ++a)
        cli_buf_printf(b, "%s%s -> %s", a ? ", " : "", k->axes[a].name, k->axes[a].physical);
    cli_buf_printf(b, "); fields ");
    for (int f = 0; f < k->nfields; ++f)
        cli_buf_printf(b, "%s%s", f ? ", " : "", k->fields[f]);
    if (k->required_fields < k->nfields)
        cli_buf_printf(b, " (the first %d required)", k->required_fields);
    cli_buf_printf(b, "\nkind gate ('mfkit validate FILE'):");
    for (int c = 0; c < k->nchecks; ++c)
        cli_buf_printf(b, " %s%s%s", k->checks[c].name, k->checks[c].needs_model ? " (needs the BRDF)" : "",
                       c + 1 < k->nchecks ? "," : "");
    cli_buf_printf(b, "\n");
}

static int table_info(int argc, char **argv)
{
    const char *pos[1];
    int npos;
    int prc = cli_opt_parse(&k_info_cmd, argc - 1, argv + 1, ~0u, NULL, NULL, pos, &npos);
    if (prc == CLI_PARSE_HELP) {
        usage(stdout);
        return 0;
    }
    if (prc)
        return prc;
    const char *file = pos[0];
    mf_table_format fmt = mf_table_format_from_path(file);
    if (!mf_table_format_readable(fmt))
        return cli_error(k_cmd, "%s: cannot read %s files (readable: .exr .dds .json .npy)", file,
                         fmt == MF_TABLE_FORMAT_UNKNOWN ? "these" : mf_table_format_name(fmt));
    mf_table t;
    mf_table_file_info info;
    char msg[1024];
    mf_status st = mf_table_read(file, &t, &info, msg, sizeof msg);
    if (st != MF_OK) {
        return fail(st, msg);
    }
    const char *storage = info.half_float ? "float16" : "float32";
    cli_buf b = {0};
    cli_buf_printf(&b, "file: %s (%s, %s, %s)\n", file, mf_table_format_name(fmt), storage,
                   info.has_metadata ? "mfkit metadata" : "no mfkit metadata: generic axes");
    describe_kind(&b, &t);
    cli_buf_printf(&b, "texels: %zu =", mf_table_texels(&t));
    for (int k = 0; k < t.naxes; ++k)
        cli_buf_printf(&b, "%s%d", k ? " x " : " ", t.axes[k].size);
    cli_buf_printf(&b, "\nrecord: %d %s fields (%d bytes), texel-major, first axis fastest: field f of texel (",
                   t.nfields, storage, t.nfields * (info.half_float ? 2 : 4));
    for (int k = 0; k < t.naxes; ++k)
        cli_buf_printf(&b, "%si%d", k ? ", " : "", k);
    cli_buf_printf(&b, ") is value (");
    for (int k = 0; k < t.naxes; ++k) {
        if (k + 1 < t.naxes)
            cli_buf_printf(&b, "i%d + %d * %s", k, t.axes[k].size, k + 2 < t.naxes ? "(" : "");
        else
            cli_buf_printf(&b, "i%d", k);
    }
    for (int k = 0; k + 2 < t.naxes; ++k)
        cli_buf_printf(&b, ")");
    cli_buf_printf(&b, ") * %d + f\n", t.nfields);
    cli_buf_printf(&b, "texel centres: texel i of n holds p = lo + (hi - lo) * i / (n - 1); a texture samples p at "
                       "uv = (p - lo) / (hi - lo) * (n - 1) / n + 0.5 / n\n");
    for (int k = 0; k < t.naxes; ++k) {
        const mf_table_axis *a = &t.axes[k];
        char desc[256];
        mf_axis_describe(a, desc, sizeof desc);
        double x0 = mf_table_axis_physical(a, a->lo), x1 = mf_table_axis_physical(a, a->hi);
        cli_buf_printf(&b, "axis %d: %s, %d texels, %s in [%.17g, %.17g], mapping %s: %s (%s from %.9g to %.9g)\n", k,
                       a->name, a->size, a->name, a->lo, a->hi, mf_axis_mapping_name(a->mapping), desc, a->physical,
                       x0, x1);
    }
    if (fmt == MF_TABLE_FORMAT_DDS && info.has_metadata) {
        cli_buf_printf(&b, "dds channels:");
        for (int c = 0; c < 4; ++c)
            cli_buf_printf(&b, " %c=%s", "RGBA"[c], t.fields[c]);
        cli_buf_printf(&b, "\n");
    }
    cli_buf_printf(&b, "fields:\n  %-5s %-31s %-16s %-16s %s\n", "index", "name", "min", "max", "nan");
    for (int f = 0; f < t.nfields; ++f) {
        double lo, hi;
        size_t nans;
        mf_table_field_range(&t, f, &lo, &hi, &nans);
        cli_buf_printf(&b, "  %-5d %-31s %-16.9g %-16.9g %zu\n", f, t.fields[f], lo, hi, nans);
    }
    cli_buf_printf(&b, "metadata:%s\n", t.nmeta ? "" : " (none)");
    for (int i = 0; i < t.nmeta; ++i)
        cli_buf_printf(&b, "  %s = %s\n", t.meta[i].key, t.meta[i].value);
    if (info.has_half_error)
        print_half_error(&b, &t, &info.half_error, 0);
    mf_table_free(&t);
    int rc = cli_buf_write(&b, stdout) == 0 ? 0 : (cli_error(k_cmd, "stdout: write failed"), 3);
    cli_buf_free(&b);
    return rc;
}

/* ---- table plot, table lobe ---------------------------------------------------------------------- */

/* "passed its gate", ... from the "validated" metadata of mfkit's writers. */
static const char *gate_verdict(const mf_table *t)
{
    const char *v = mf_table_get_meta(t, "validated");
    if (!v)
        return "gate not recorded in the file (run mfkit validate)";
    if (!strcmp(v, "true"))
        return "passed its gate";
    if (!strcmp(v, "false"))
        return "FAILED its gate (written with --force)";
    return "gate: unknown \"validated\" value";
}

/* The file name's stem of a table argument ("P_1.dds+P_2.dds" -> "P"). */
static void table_stem(const char *arg, char *out, size_t size)
{
    const char *plus = strchr(arg, '+');
    size_t len = plus ? (size_t)(plus - arg) : strlen(arg);
    const char *base = arg;
    for (size_t i = 0; i < len; ++i)
        if (arg[i] == '/')
            base = arg + i + 1;
    len -= (size_t)(base - arg);
    const char *dot = NULL;
    for (size_t i = 0; i < len; ++i)
        if (base[i] == '.')
            dot = base + i;
    if (dot && dot != base)
        len = (size_t)(dot - base);
    if (plus && len > 2 && base[len - 2] == '_' && base[len - 1] == '1')
        len -= 2;
    if (len >= size)
        len = size - 1;
    memcpy(out, base, len);
    out[len] = '\0';
    if (!out[0])
        snprintf(out, size, "table");
}

static void csv_comment_meta(cli_buf *b, const char *arg, const mf_table *t)
{
    char why[256];
    const mf_table_kind *k = mf_table_kind_of(t, why, sizeof why);
    cli_buf_printf(b, "# command=mfkit table, mfkit=%s\n# table: %s\n# kind: %s\n# gate: %s\n", MFKIT_VERSION, arg,
                   k ? k->name : "none", gate_verdict(t));
    const char *brdf = mf_table_get_meta(t, "brdf");
    if (brdf)
        cli_buf_printf(b, "# brdf: %s\n", brdf);
}

static int table_plot(int argc, char **argv)
{
    const char *cmd = "table plot";
    cli_val v[P_NOPTS];
    const char *pos[1];
    int npos;
    int prc = cli_opt_parse(&k_plot_cmd, argc - 1, argv + 1, ~0u, NULL, v, pos, &npos);
    if (prc == CLI_PARSE_HELP) {
        cli_opt_usage(&k_plot_cmd, stdout);
        return 0;
    }
    if (prc)
        return prc;
    int plots = !v[P_NO_PLOTS].set;
    if (plots && (prc = cli_plot_available(cmd)) != 0)
        return prc;
    mf_table t;
    int rc = cli_read_any_table(cmd, pos[0], &t, NULL);
    if (rc)
        return rc;
    char stem[256], name[400];
    table_stem(pos[0], stem, sizeof stem);
    cli_buf b = {0};
    csv_comment_meta(&b, pos[0], &t);
    /* every texel: indices, parameters, physical values, fields (mf_table's order: first axis fastest) */
    for (int k = 0; k < t.naxes; ++k)
        cli_buf_printf(&b, "%si%d", k ? "," : "", k);
    for (int k = 0; k < t.naxes; ++k)
        cli_buf_printf(&b, ",%s", t.axes[k].name);
    for (int k = 0; k < t.naxes; ++k)
        cli_buf_printf(&b, ",phys_%s", t.axes[k].physical);
    for (int f = 0; f < t.nfields; ++f)
        cli_buf_printf(&b, ",%s", t.fields[f]);
    cli_buf_printf(&b, "\n");
    size_t n = mf_table_texels(&t);
    int idx[MF_TABLE_MAX_AXES] = {0};
    for (size_t i = 0; i < n; ++i) {
        for (int k = 0; k < t.naxes; ++k)
            cli_buf_printf(&b, "%s%d", k ? "," : "", idx[k]);
        for (int k = 0; k < t.naxes; ++k) {
            cli_buf_printf(&b, ",");
            cli_buf_double(&b, mf_table_axis_param(&t.axes[k], idx[k]));
        }
        for (int k = 0; k < t.naxes; ++k) {
            cli_buf_printf(&b, ",");
            cli_buf_double(&b, mf_table_axis_physical(&t.axes[k], mf_table_axis_param(&t.axes[k], idx[k])));
        }
        for (int f = 0; f < t.nfields; ++f) {
            cli_buf_printf(&b, ",");
            cli_buf_double(&b, t.data[i * (size_t)t.nfields + (size_t)f]);
        }
        cli_buf_printf(&b, "\n");
        for (int k = 0; k < t.naxes; ++k) {
            if (++idx[k] < t.axes[k].size)
                break;
            idx[k] = 0;
        }
    }
    cli_outdir od;
    char msg[1024];
    rc = cli_outdir_open(cmd, &od, v[P_OUT].s);
    if (!rc) {
        snprintf(name, sizeof name, "%s_fields.csv", stem);
        const char *csv = cli_outdir_path(&od, name);
        if (cli_buf_write_file_atomic(&b, csv, msg, sizeof msg) != 0)
            rc = CLI_EXIT_IO, cli_error(cmd, "%s", msg);
        if (!rc && plots) {
            for (int f = 0; f < t.nfields; ++f) {
                snprintf(name, sizeof name, "%s_%s.png", stem, t.fields[f]);
                cli_outdir_path(&od, name);
            }
            const char *args[] = {"fields", csv, od.dir, stem, NULL};
            rc = cli_plot_run(cmd, args);
        }
        if (rc)
            cli_outdir_abort(&od);
    }
    cli_buf_free(&b);
    if (!rc)
        printf("%s/%s_fields.csv%s (%d fields, %s)\n", od.dir, stem, plots ? " and one PNG per field" : "", t.nfields,
               gate_verdict(&t));
    mf_table_free(&t);
    return rc;
}

static int table_lobe(int argc, char **argv)
{
    const char *cmd = "table lobe";
    cli_val v[L_NOPTS];
    const char *pos[1];
    int npos;
    int prc = cli_opt_parse(&k_lobe_cmd, argc - 1, argv + 1, ~0u, NULL, v, pos, &npos);
    if (prc == CLI_PARSE_HELP) {
        cli_opt_usage(&k_lobe_cmd, stdout);
        return 0;
    }
    if (prc)
        return prc;
    if (v[L_AT].set == (v[L_ALPHA].set || v[L_THETA].set))
        return cli_error(cmd, "give the point either as --at R,U or as --alpha A --theta DEG");
    if (!v[L_AT].set && !(v[L_ALPHA].set && v[L_THETA].set))
        return cli_error(cmd, "--alpha and --theta go together");
    int plots = !v[L_NO_PLOTS].set, npts = v[L_POINTS].set ? (int)v[L_POINTS].i : 361;
    mf_table t;
    int rc = cli_read_any_table(cmd, pos[0], &t, NULL);
    if (rc)
        return rc;
    char why[256];
    const mf_table_kind *k = mf_table_kind_of(&t, why, sizeof why);
    if (!k || strcmp(k->name, "ltc_isotropic") != 0) {
        rc = cli_error(cmd, "%s: %s%s; lobes are drawn for ltc_isotropic tables", pos[0], k ? "a " : "no known kind: ",
                       k ? k->name : why);
        mf_table_free(&t);
        return rc;
    }
    const char *bname = v[L_BRDF].set ? v[L_BRDF].s : mf_table_get_meta(&t, "brdf");
    const mf_brdf_model *model = bname ? mf_brdf_model_find(bname) : NULL;
    if (!model) {
        rc = bname ? cli_error(cmd, "unknown BRDF '%s' (see 'mfkit fit ltc --list' for the names)", bname)
                   : cli_error(cmd, "%s names no BRDF (\"brdf\" metadata): give --brdf NAME", pos[0]);
        mf_table_free(&t);
        return rc;
    }
    double p[2];
    if (v[L_AT].set) {
        p[0] = v[L_AT].lo;
        p[1] = v[L_AT].hi;
    } else {
        p[0] = sqrt(v[L_ALPHA].d);                        /* alpha = r^2 */
        p[1] = sqrt(1.0 - cos(v[L_THETA].d * MF_PI / 180.0)); /* cos theta_o = 1 - u^2 */
    }
    for (int a = 0; a < 2; ++a) {
        const mf_table_axis *ax = &t.axes[a];
        if (!(p[a] >= fmin(ax->lo, ax->hi) && p[a] <= fmax(ax->lo, ax->hi))) {
            rc = cli_error(cmd, "%s %.6g is outside the table's range [%.6g, %.6g]%s", ax->name, p[a], ax->lo, ax->hi,
                           v[L_AT].set ? "" : " (from --alpha/--theta)");
            mf_table_free(&t);
            return rc;
        }
    }
    if (plots && (rc = cli_plot_available(cmd)) != 0) {
        mf_table_free(&t);
        return rc;
    }
    double *rec = malloc(sizeof *rec * (size_t)t.nfields);
    mf_ltc ltc;
    int fm[5];
    for (int f = 0; f < 5; ++f)
        fm[f] = mf_table_field(&t, mf_ltc_table_fields[f]);
    if (!rec || mf_table_lookup(&t, p, rec) != MF_OK) {
        free(rec);
        mf_table_free(&t);
        return cli_error(cmd, "out of memory"), CLI_EXIT_IO;
    }
    double m4[4] = {rec[fm[0]], rec[fm[1]], rec[fm[2]], rec[fm[3]]}, mag = rec[fm[4]];
    free(rec);
    if (mf_ltc_table_unpack(m4, &ltc) != MF_OK || !isfinite(mag)) {
        mf_table_free(&t);
        return cli_error(cmd, "%s: the record at r = %g, u = %g is not a usable LTC (singular matrix or NaN)", pos[0],
                         p[0], p[1]), CLI_EXIT_IO;
    }
    double alpha = mf_table_axis_physical(&t.axes[0], p[0]), ct = mf_table_axis_physical(&t.axes[1], p[1]);
    mf_vec3 wo = mf_ltc_gate_view(ct);
    mf_brdf_params prm = mf_brdf_params_iso(alpha);
    double st = sqrt(fmax(0.0, 1.0 - ct * ct));
    mf_vec3 wr = mf_vec3_make(-st, 0.0, ct);
    cli_buf b = {0};
    csv_comment_meta(&b, pos[0], &t);
    cli_buf_printf(&b, "# point: r=%.17g, u=%.17g, alpha=%.17g, theta_o_deg=%.17g, magnitude=%.17g, brdf=%s\n", p[0],
                   p[1], alpha, acos(ct) * 180.0 / MF_PI, mag, model->name);
    cli_buf_printf(&b, "# ltc = magnitude * D_LTC(wi), brdf = f(wo, wi) wi.z (per steradian); wo = (%.17g, 0, %.17g)\n",
                   wo.x, wo.z);
    cli_buf_printf(&b, "slice,s_deg,wi_x,wi_y,wi_z,ltc,brdf\n");
    for (int sl = 0; sl < 2; ++sl)
        for (int i = 0; i < npts; ++i) {
            double s = -90.0 + 180.0 * (double)i / (double)(npts - 1), sr = s * MF_PI / 180.0;
            mf_vec3 wi = sl == 0 ? mf_vec3_make(sin(sr), 0.0, cos(sr))
                                 : mf_vec3_add(mf_vec3_scale(wr, cos(sr)), mf_vec3_make(0.0, sin(sr), 0.0));
            if (wi.z < 0.0)
                wi.z = 0.0; /* -0 and rounding at the horizon */
            double l = wi.z > 0.0 ? mag * mf_ltc_eval(&ltc, wi) : 0.0;
            double f = wi.z > 0.0 ? model->eval_cos(model, &prm, wo, wi) : 0.0;
            cli_buf_printf(&b, "%s,", sl == 0 ? "incidence" : "perpendicular");
            double vals[6] = {s, wi.x, wi.y, wi.z, l, f};
            for (int j = 0; j < 6; ++j) {
                cli_buf_double(&b, vals[j]);
                cli_buf_printf(&b, j < 5 ? "," : "\n");
            }
        }
    cli_outdir od;
    char msg[1024];
    rc = cli_outdir_open(cmd, &od, v[L_OUT].s);
    if (!rc) {
        const char *csv = cli_outdir_path(&od, "lobe.csv");
        if (cli_buf_write_file_atomic(&b, csv, msg, sizeof msg) != 0)
            rc = CLI_EXIT_IO, cli_error(cmd, "%s", msg);
        if (!rc && plots) {
            cli_outdir_path(&od, "lobe.png");
            const char *args[] = {"lobe", csv, od.dir, NULL};
            rc = cli_plot_run(cmd, args);
        }
        if (rc)
            cli_outdir_abort(&od);
    }
    cli_buf_free(&b);
    if (!rc)
        printf("%s/lobe.csv%s: %s at alpha %.4g, theta_o %.2f deg (r %.4g, u %.4g), magnitude %.4g, BRDF %s\n", od.dir,
               plots ? " and lobe.png" : "", pos[0], alpha, acos(ct) * 180.0 / MF_PI, p[0], p[1], mag, model->name);
    mf_table_free(&t);
    return rc;
}

int cli_table(int argc, char **argv)
{
    if (argc < 2)
        return cli_error(k_cmd, "needs a subcommand: convert, info, plot or lobe (see 'mfkit table --help')");
    const char *sub = argv[1];
    if (!strcmp(sub, "--help") || !strcmp(sub, "-h") || !strcmp(sub, "help")) {
        usage(stdout);
        return 0;
    }
    if (!strcmp(sub, "convert"))
        return table_convert(argc - 1, argv + 1);
    if (!strcmp(sub, "info"))
        return table_info(argc - 1, argv + 1);
    if (!strcmp(sub, "plot"))
        return table_plot(argc - 1, argv + 1);
    if (!strcmp(sub, "lobe"))
        return table_lobe(argc - 1, argv + 1);
    return cli_error(k_cmd, "unknown subcommand '%s' (convert, info, plot, lobe)", sub);
}

