# Shared by the GNSS-SDR scripts: TOML pieces of their scenarios.
#
# paper_session ORDER [GAMMA]
#   the session start, the paper's OCXO with its Γ (or GAMMA, a TOML array in
#   Hz/(m/s²), e.g. "[-0.05, 0.12, 0.03]") and a 3 Hz loop of ORDER.
paper_session() {
    local gamma=${2:-[0.09, 0.08, -0.08]}
    printf '[session]\nstart_utc = "2024-02-08T12:00:00Z"\n[oscillator]\npreset = "ocxo"\n'
    printf 'gamma_hz_per_mps2 = %s\n[loop]\norder = %s\nbn_hz = 3.0\n' "$gamma" "$1"
}

#
# shake_sequence FIRST_REST_S SHAKE_S REST_S [JITTER]
#   rest FIRST_REST_S, then x, y, z each shaken for SHAKE_S at a 1.1 s period
#   and 3 m/s², each followed by REST_S of rest; JITTER=1 adds the paper's 7 %
#   period and amplitude jitter.
shake_sequence() {
    local first=$1 shake=$2 rest=$3 jitter=${4:-0}
    printf '[[motion.segments]]\nkind = "rest"\nduration_s = %s\n' "$first"
    for axis in x y z; do
        printf '[[motion.segments]]\nkind = "shake"\naxis = "%s"\nduration_s = %s\nperiod_s = 1.1\namplitude_mps2 = 3.0\n' \
            "$axis" "$shake"
        if [ "$jitter" = 1 ]; then
            echo 'jitter = { period_rel = 0.07, amplitude_rel = 0.07, correlation_s = 3.0 }'
        fi
        printf '[[motion.segments]]\nkind = "rest"\nduration_s = %s\n' "$rest"
    done
}
