/*
 * cli_table.c -- `mfkit table convert IN OUT` and `mfkit table info FILE`: table files between
 * the formats of mf_table_io.h (docs/tables.md, docs/cli.md).
 * Exit code 0 on success, 2 for a usage error, 3 for an I/O or format error; errors are one line
 * on stderr, and a failed convert leaves no output file (the writers are atomic).
 */
#include "cli.h"
#include "cli_opt.h"
#include "cli_util.h"

#include <string.h>

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

static void usage(FILE *f)
{
    cli_opt_usage(&k_convert_cmd, f);
    fputc('\n', f);
    cli_opt_usage(&k_info_cmd, f);
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

int cli_table(int argc, char **argv)
{
    if (argc < 2)
        return cli_error(k_cmd, "needs a subcommand: convert or info (see 'mfkit table --help')");
    const char *sub = argv[1];
    if (!strcmp(sub, "--help") || !strcmp(sub, "-h") || !strcmp(sub, "help")) {
        usage(stdout);
        return 0;
    }
    if (!strcmp(sub, "convert"))
        return table_convert(argc - 1, argv + 1);
    if (!strcmp(sub, "info"))
        return table_info(argc - 1, argv + 1);
    return cli_error(k_cmd, "unknown subcommand '%s' (convert, info)", sub);
}

