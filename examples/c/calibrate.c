/*
 * gsens C API example: calibrate from an epoch series, as receiver firmware
 * would, with the calibrator in memory the program owns (no allocation).
 *
 *   calibrate EPOCHS.csv RESULT.json
 *   calibrate EPOCHS.csv ORDER BN_HZ ZETA LOOP_INTERVAL_S LOG_INTERVAL_S LOGGED WARMUP_S HIGHPASS_HZ
 *
 * EPOCHS.csv is what `gsens estimate --epochs-out` writes: a header line,
 * then t_s,phase_err_rad,fx_mps2,fy_mps2,fz_mps2 per epoch (phase empty
 * where no channel had one). The loop and the estimator's settings come
 * either from the result document of the same `gsens estimate` run (`--json`:
 * its `loop_used`, the loop Γ̂ is under, which may be the stated loop moved
 * within its tolerance, with `log_interval_s` and the `settings`' logged
 * phase, warm-up and high-pass) or from the arguments (LOGGED is "last" or
 * "mean"). It prints Γ̂ ± σ per axis (17 significant digits), then a
 * compensation check: the NCO correction for the first epoch's specific force.
 *
 * Build (README.md, "The C API, step by step"):
 *   cargo build --release -p gsens-ffi
 *   cc -std=c11 -O2 examples/c/calibrate.c -Icrates/gsens-ffi/include \
 *      target/release/libgsens_ffi.a -lm -lpthread -ldl -o calibrate
 */
#include <math.h>
#include <stdalign.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gsens.h"

/* The calibrator's memory: static, sized and aligned generously; checked at run time. */
static alignas(64) unsigned char calibrator_memory[4096];

static int check(GsensStatus s, const char *what) {
    if (s != GSENS_STATUS_OK) {
        fprintf(stderr, "calibrate: %s: %s\n", what, gsens_status_message((int32_t)s));
        return 0;
    }
    return 1;
}

/* The text of a whole file (NUL-terminated), or NULL. */
static char *read_text(const char *path) {
    FILE *f = fopen(path, "rb");
    if (!f) return NULL;
    size_t cap = 1 << 16, len = 0;
    char *text = malloc(cap);
    size_t got;
    while (text && (got = fread(text + len, 1, cap - len - 1, f)) > 0) {
        len += got;
        if (cap - len - 1 == 0) {
            char *bigger = realloc(text, cap *= 2);
            if (!bigger) free(text);
            text = bigger;
        }
    }
    fclose(f);
    if (text) text[len] = '\0';
    return text;
}

/*
 * Where the value of "key" starts in the JSON text at or after `from` (NULL:
 * not found). Enough for the result document's unique keys, read in their
 * order of appearance within one object; not a general JSON parser.
 */
static const char *json_value(const char *from, const char *key) {
    char quoted[64];
    snprintf(quoted, sizeof quoted, "\"%s\"", key);
    const char *at = from ? strstr(from, quoted) : NULL;
    if (!at) return NULL;
    at += strlen(quoted);
    while (*at == ' ' || *at == '\n' || *at == '\r' || *at == '\t') at++;
    if (*at != ':') return NULL;
    at++;
    while (*at == ' ' || *at == '\n' || *at == '\r' || *at == '\t') at++;
    return at;
}

static int json_number(const char *from, const char *key, double *out) {
    const char *v = json_value(from, key);
    char *end;
    if (!v) return 0;
    *out = strtod(v, &end);
    return end != v;
}

/* Whether the string value of "key" is `want`. */
static int json_string_is(const char *from, const char *key, const char *want) {
    const char *v = json_value(from, key);
    size_t n = strlen(want);
    return v && v[0] == '"' && strncmp(v + 1, want, n) == 0 && v[1 + n] == '"';
}

/* The loop Γ̂ is under and the estimator's settings, from a `gsens estimate --json` document. */
static int config_from_document(const char *path, GsensCalibratorConfig *config) {
    char *doc = read_text(path);
    if (!doc) {
        perror(path);
        return 0;
    }
    const char *loop = json_value(doc, "loop_used");
    const char *spec = loop ? json_value(loop, "spec") : NULL;
    const char *settings = json_value(doc, "settings");
    int ok = loop && spec && settings && json_string_is(loop, "implementation", "kaplan");
    if (ok && json_string_is(spec, "kind", "second_order")) {
        config->order = 2;
        ok = json_number(spec, "bn_hz", &config->bn_hz) && json_number(spec, "zeta", &config->zeta);
    } else if (ok && json_string_is(spec, "kind", "third_order")) {
        config->order = 3;
        ok = json_number(spec, "bn_hz", &config->bn_hz) && json_number(spec, "a3", &config->a3) &&
             json_number(spec, "b3", &config->b3);
    } else {
        ok = 0;
    }
    if (!ok) {
        fprintf(stderr, "%s: no `loop_used` with a Kaplan loop of order 2 or 3 (this example models those)\n", path);
        free(doc);
        return 0;
    }
    ok = json_number(loop, "interval_s", &config->loop_interval_s) &&
         json_number(doc, "log_interval_s", &config->log_interval_s) &&
         json_number(settings, "warmup_s", &config->warmup_s) &&
         json_number(settings, "highpass_hz", &config->highpass_hz);
    config->logged_phase =
        json_string_is(settings, "logged_phase", "mean") ? GSENS_LOGGED_PHASE_MEAN : GSENS_LOGGED_PHASE_LAST;
    if (!ok) fprintf(stderr, "%s: not a gsens result document (loop_used, log_interval_s, settings)\n", path);
    free(doc);
    return ok;
}

int main(int argc, char **argv) {
    if (argc != 3 && argc != 10) {
        fprintf(stderr,
                "usage: %s EPOCHS.csv RESULT.json\n"
                "       %s EPOCHS.csv ORDER BN_HZ ZETA LOOP_INTERVAL_S LOG_INTERVAL_S last|mean WARMUP_S HIGHPASS_HZ\n",
                argv[0], argv[0]);
        return 2;
    }
    GsensCalibratorConfig config;
    if (!check(gsens_calibrator_config_default(&config), "default configuration")) return 1;
    if (argc == 3) {
        if (!config_from_document(argv[2], &config)) return 1;
    } else {
        config.order = (uint32_t)atoi(argv[2]);
        config.bn_hz = atof(argv[3]);
        config.zeta = atof(argv[4]);
        config.loop_interval_s = atof(argv[5]);
        config.log_interval_s = atof(argv[6]);
        config.logged_phase = strcmp(argv[7], "mean") == 0 ? GSENS_LOGGED_PHASE_MEAN : GSENS_LOGGED_PHASE_LAST;
        config.warmup_s = atof(argv[8]);
        config.highpass_hz = atof(argv[9]);
    }

    if (gsens_calibrator_size() > sizeof calibrator_memory || gsens_calibrator_align() > 64) {
        fprintf(stderr, "calibrate: the calibrator needs %zu bytes aligned to %zu\n", gsens_calibrator_size(),
                gsens_calibrator_align());
        return 1;
    }
    GsensCalibrator *cal = NULL;
    if (!check(gsens_calibrator_init(calibrator_memory, sizeof calibrator_memory, &config, &cal), "init")) return 1;

    FILE *f = fopen(argv[1], "r");
    if (!f) {
        perror(argv[1]);
        return 1;
    }
    char line[512];
    unsigned long lineno = 0;
    double first_accel[3] = {0, 0, 0};
    int have_first = 0;
    while (fgets(line, sizeof line, f)) {
        lineno++;
        if (lineno == 1) continue; /* the header */
        double t, accel[3];
        char phase_text[64];
        /* t,phase,fx,fy,fz with the phase possibly empty. */
        char *p = line, *fields[5];
        for (int k = 0; k < 5; k++) {
            fields[k] = p;
            p = strchr(p, k < 4 ? ',' : '\n');
            if (!p && k < 4) {
                fprintf(stderr, "%s:%lu: expected 5 fields\n", argv[1], lineno);
                return 1;
            }
            if (p) *p++ = '\0';
        }
        t = atof(fields[0]);
        (void)t;
        snprintf(phase_text, sizeof phase_text, "%s", fields[1]);
        double phase = phase_text[0] ? atof(phase_text) : NAN;
        for (int i = 0; i < 3; i++) accel[i] = strtod(fields[2 + i], NULL);
        if (!have_first) {
            memcpy(first_accel, accel, sizeof accel);
            have_first = 1;
        }
        if (!check(gsens_calibrator_feed(cal, accel, phase), "feed")) {
            fprintf(stderr, "%s:%lu\n", argv[1], lineno);
            return 1;
        }
    }
    fclose(f);
    if (!check(gsens_calibrator_finish(cal), "finish")) return 1;

    GsensEstimate e;
    e.struct_size = sizeof e;
    if (!check(gsens_calibrator_estimate(cal, &e), "estimate")) return 1;
    const char *axes = "xyz";
    for (int i = 0; i < 3; i++) {
        if (e.observable[i])
            printf("gamma_%c %.17g %.17g\n", axes[i], e.gamma_hz_per_mps2[i], e.sigma_hz_per_mps2[i]);
        else
            printf("gamma_%c unobservable\n", axes[i]);
    }
    printf("epochs %llu of %llu, residual %.6g rad\n", (unsigned long long)e.epochs_used,
           (unsigned long long)e.epochs_fed, e.residual_sigma_rad);

    GsensCompensator comp;
    double gamma[3];
    for (int i = 0; i < 3; i++) gamma[i] = e.observable[i] ? e.gamma_hz_per_mps2[i] : 0.0;
    double correction_hz = 0;
    if (!check(gsens_compensator_init(gamma, 1.0, &comp), "compensator")) return 1;
    if (!check(gsens_compensator_nco_correction_hz(&comp, first_accel, &correction_hz), "correction")) return 1;
    printf("nco_correction_hz %.17g\n", correction_hz);
    return check(gsens_calibrator_drop(cal), "drop") ? 0 : 1;
}
