/*
 * gpu_osmesa.h -- what the software-GPU tests (test_gpu_ltc.c, test_gpu_ltc_aniso.c) share: an
 * OpenGL 3.3 core context on Mesa's OSMesa (llvmpipe), float textures, one full-screen draw of a
 * fragment shader into a GL_RGBA32F framebuffer read back as floats, and small file helpers.
 * Include after mf_test.h; define GL_GLEXT_PROTOTYPES before.
 */
#ifndef MF_GPU_OSMESA_H
#define MF_GPU_OSMESA_H

#include <GL/osmesa.h>
#include <GL/gl.h>
#include <GL/glext.h>

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* Under LeakSanitizer (tests/test_sanitize.sh): Mesa 22.3's OSMesa keeps a few hundred bytes of
 * its framebuffer state per process (allocated in OSMesaMakeCurrent, never freed on destroy);
 * leaks whose stack is inside libOSMesa are not ours.  (The sanitizer runtime's documented hook;
 * unused without it.) */
const char *__lsan_default_suppressions(void);
const char *__lsan_default_suppressions(void) { return "leak:libOSMesa.so"; }

/* system(cmd), printing the command when it fails; 1 on success. */
static inline int gpu_run(const char *cmd)
{
    int rc = system(cmd);
    if (rc != 0)
        fprintf(stderr, "command failed (%d): %s\n", rc, cmd);
    return rc == 0;
}

/* The whole file as a NUL-terminated string (malloc), or NULL. */
static inline char *gpu_read_all(const char *path)
{
    FILE *f = fopen(path, "rb");
    if (!f)
        return NULL;
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    char *s = n >= 0 ? malloc((size_t)n + 1) : NULL;
    if (s && fread(s, 1, (size_t)n, f) != (size_t)n) {
        free(s);
        s = NULL;
    }
    if (s)
        s[n] = 0;
    fclose(f);
    return s;
}

/* Writes text to path; 1 on success. */
static inline int gpu_write_file(const char *path, const char *a, const char *b, const char *c)
{
    FILE *f = fopen(path, "w");
    if (!f)
        return 0;
    fputs(a, f);
    if (b)
        fputs(b, f);
    if (c)
        fputs(c, f);
    return fclose(f) == 0;
}

/* The OSMesa context: GL 3.3 core, made current on a dummy 4 x 4 buffer (the draws go to an FBO).
 * NULL (with a failure recorded) when Mesa's libosmesa6 with llvmpipe is missing. */
static inline OSMesaContext gpu_context(void)
{
    static unsigned char dummy[4 * 4 * 4];
    const int attribs[] = {OSMESA_FORMAT, OSMESA_RGBA, OSMESA_DEPTH_BITS, 0, OSMESA_PROFILE, OSMESA_CORE_PROFILE,
                           OSMESA_CONTEXT_MAJOR_VERSION, 3, OSMESA_CONTEXT_MINOR_VERSION, 3, 0};
    OSMesaContext ctx = OSMesaCreateContextAttribs(attribs, NULL);
    if (!ctx) {
        MF_FAIL_AT("OSMesa: cannot create an OpenGL 3.3 core context (Mesa's libosmesa6 with llvmpipe is needed)");
        return NULL;
    }
    if (!OSMesaMakeCurrent(ctx, dummy, GL_UNSIGNED_BYTE, 4, 4)) {
        MF_FAIL_AT("OSMesa: cannot make the context current");
        OSMesaDestroyContext(ctx);
        return NULL;
    }
    printf("GL: %s, %s\n", (const char *)glGetString(GL_VERSION), (const char *)glGetString(GL_RENDERER));
    return ctx;
}

static inline GLuint gpu_compile(GLenum type, const char *src)
{
    GLuint s = glCreateShader(type);
    glShaderSource(s, 1, &src, NULL);
    glCompileShader(s);
    GLint ok = 0;
    glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
    if (!ok) {
        char log[4096];
        glGetShaderInfoLog(s, sizeof log, NULL, log);
        MF_FAIL_AT("the GL driver refused the shader: %s", log);
    }
    return s;
}

/* A w x h GL_RGBA32F texture on texture unit `unit` (row 0 of rgba at t = 0), clamp-to-edge, no mipmaps. */
static inline GLuint gpu_float_texture(int unit, int w, int h, const float *rgba, GLenum filter)
{
    GLuint tex;
    glGenTextures(1, &tex);
    glActiveTexture(GL_TEXTURE0 + (GLenum)unit);
    glBindTexture(GL_TEXTURE_2D, tex);
    glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA32F, w, h, 0, GL_RGBA, GL_FLOAT, rgba);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, (GLint)filter);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, (GLint)filter);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAX_LEVEL, 0);
    return tex;
}

/* Links the full-screen triangle with the fragment shader frag_src; 0 on failure (recorded). */
static inline GLuint gpu_program(const char *frag_src)
{
    const char *vs = "#version 330 core\nvoid main() {\n"
                     "    vec2 p = vec2(float((gl_VertexID << 1) & 2), float(gl_VertexID & 2));\n"
                     "    gl_Position = vec4(p * 2.0 - 1.0, 0.0, 1.0);\n}\n";
    GLuint prog = glCreateProgram();
    GLuint v = gpu_compile(GL_VERTEX_SHADER, vs), f = gpu_compile(GL_FRAGMENT_SHADER, frag_src);
    glAttachShader(prog, v);
    glAttachShader(prog, f);
    glLinkProgram(prog);
    glDeleteShader(v);
    glDeleteShader(f);
    GLint linked = 0;
    glGetProgramiv(prog, GL_LINK_STATUS, &linked);
    if (!linked) {
        MF_FAIL_AT("the GL driver did not link the program");
        glDeleteProgram(prog);
        return 0;
    }
    return prog;
}

/* Draws the bound program over a w x h GL_RGBA32F target (texture unit `unit`) and reads it back
 * into pix (4 w h floats, row 0 first); 1 on success. */
static inline int gpu_draw(int unit, int w, int h, float *pix)
{
    GLuint fbo, target, vao;
    glGenTextures(1, &target);
    glActiveTexture(GL_TEXTURE0 + (GLenum)unit);
    glBindTexture(GL_TEXTURE_2D, target);
    glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA32F, w, h, 0, GL_RGBA, GL_FLOAT, NULL);
    glGenFramebuffers(1, &fbo);
    glBindFramebuffer(GL_FRAMEBUFFER, fbo);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, target, 0);
    int ok = glCheckFramebufferStatus(GL_FRAMEBUFFER) == GL_FRAMEBUFFER_COMPLETE;
    CHECK(ok);
    glGenVertexArrays(1, &vao);
    glBindVertexArray(vao);
    glViewport(0, 0, w, h);
    glDrawArrays(GL_TRIANGLES, 0, 3);
    glReadPixels(0, 0, w, h, GL_RGBA, GL_FLOAT, pix);
    GLenum err = glGetError();
    if (err != GL_NO_ERROR) {
        MF_FAIL_AT("GL error 0x%x", err);
        ok = 0;
    }
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glDeleteVertexArrays(1, &vao);
    glDeleteFramebuffers(1, &fbo);
    glDeleteTextures(1, &target);
    return ok;
}

/* wgsl (a NUL-terminated module with a fragment entry point `main`) translated to GLSL 3.30 by naga:
 * node NODE_DIR/wgsl_to_glsl.mjs (tests/node; tests/test_engines.sh installs naga-wasm beside it).
 * Each texture with its sampler becomes the sampler2D _group_0_binding_<texture binding>_fs.  NULL
 * (with a failure recorded) on any error. */
static inline char *gpu_wgsl_to_glsl(const char *wgsl, const char *node_dir)
{
    char dir[] = "/tmp/mfkit_gpu_wgslXXXXXX", in[600], out[600], cmd[2048];
    if (!mkdtemp(dir)) {
        MF_FAIL_AT("cannot create a temporary directory");
        return NULL;
    }
    snprintf(in, sizeof in, "%s/run.wgsl", dir);
    snprintf(out, sizeof out, "%s/run.frag", dir);
    char *glsl = NULL;
    if (gpu_write_file(in, wgsl, NULL, NULL)) {
        snprintf(cmd, sizeof cmd, "node %s/wgsl_to_glsl.mjs %s %s main", node_dir, in, out);
        if (gpu_run(cmd))
            glsl = gpu_read_all(out);
    }
    if (!glsl)
        MF_FAIL_AT("the WGSL could not be translated by naga (%s/wgsl_to_glsl.mjs)", node_dir);
    snprintf(cmd, sizeof cmd, "rm -rf %s", dir);
    if (system(cmd) != 0)
        fprintf(stderr, "could not remove %s\n", dir);
    return glsl;
}

#endif /* MF_GPU_OSMESA_H */
