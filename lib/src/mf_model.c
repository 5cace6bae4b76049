/* mf_model.c -- the registry of the BRDF models that LTC tables are fitted to (mf_model.h). */
#include "mfkit/mf_model.h"

#include <stddef.h>

#include <string.h>

extern const mf_brdf_model mf_model_ggx;
extern const mf_brdf_model mf_model_beckmann;
extern const mf_brdf_model mf_model_lambert;
extern const mf_brdf_model mf_model_oren_nayar;
extern const mf_brdf_model mf_model_disney;
extern const mf_brdf_model mf_model_charlie;

const mf_brdf_model *const mf_brdf_models[] = {&mf_model_ggx,        &mf_model_beckmann, &mf_model_lambert,
                                               &mf_model_oren_nayar, &mf_model_disney,   &mf_model_charlie,
                                               NULL};

const mf_brdf_model *mf_brdf_model_find(const char *name)
{
    if (!name)
        return NULL;
    for (int i = 0; mf_brdf_models[i]; ++i)
        if (!strcmp(mf_brdf_models[i]->name, name))
            return mf_brdf_models[i];
    return NULL;
}
