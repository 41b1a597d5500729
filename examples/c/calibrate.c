/*
 * gsens C API example: calibrate from an epoch series, as receiver firmware
 * would, with the calibrator in memory the program owns (no allocation).
 *
 *   calibrate EPOCHS.csv ORDER BN_HZ ZETA LOOP_INTERVAL_S LOG_INTERVAL_S LOGGED WARMUP_S HIGHPASS_HZ
 *
 * EPOCHS.csv is what `gsens estimate --epochs-out` writes: a header line,
 * then t_s,phase_err_rad,fx_mps2,fy_mps2,fz_mps2 per epoch (phase empty
 * where no channel had one). LOGGED is "last" or "mean". It prints Γ̂ ± σ
 * per axis (17 significant digits), then a compensation check: the NCO
 * correction for the first epoch's specific force.
 *
 * Build (the tests do): cc calibrate.c -I crates/gsens-ffi/include
 *   target/release/libgsens_ffi.a -lm -lpthread -ldl
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

int main(int argc, char **argv) {
    if (argc != 10) {
        fprintf(stderr,
                "usage: %s EPOCHS.csv ORDER BN_HZ ZETA LOOP_INTERVAL_S LOG_INTERVAL_S last|mean WARMUP_S HIGHPASS_HZ\n",
                argv[0]);
        return 2;
    }
    GsensCalibratorConfig config;
    if (!check(gsens_calibrator_config_default(&config), "default configuration")) return 1;
    config.order = (uint32_t)atoi(argv[2]);
    config.bn_hz = atof(argv[3]);
    config.zeta = atof(argv[4]);
    config.loop_interval_s = atof(argv[5]);
    config.log_interval_s = atof(argv[6]);
    config.logged_phase = strcmp(argv[7], "mean") == 0 ? GSENS_LOGGED_PHASE_MEAN : GSENS_LOGGED_PHASE_LAST;
    config.warmup_s = atof(argv[8]);
    config.highpass_hz = atof(argv[9]);

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
