#!/usr/bin/env python3
"""Makes crates/gsens-gnss-sdr/tests/fixtures/mat-v21*/trk_ch_5.mat: the
arrays of the real GNSS-SDR 0.0.17 run in fixtures/mat/trk_ch_0.mat, named and
typed as GNSS-SDR 0.0.21's save_matfile writes them (dll_pll_veml_tracking.cc
at tag v0.0.21: 19 float, PRN_start_sample_count and TOW_ms uint64, aux2
double, PRN uint32, WN int32, each N x 1), with TOW_ms = 345600000 + k and
WN = 2391 (in mat-v21-wn the last WN is -1, which the .dat's uint32 cannot
hold). Written by libhdf5 (h5py) rather than matio, in the oldest file format
(superblock 0, as matio) with a 512-byte MATLAB header, and with the data
layouts spread over what HDF5 offers: deflated chunks of 100 records (the
last one partly outside the array), contiguous, and compact arrays.

Also the seeds of the gnss_sdr_mat fuzz target (fuzz/seeds/gnss_sdr_mat):
the first 8 records of fixtures/mat/trk_ch_0.mat and of
fixtures/kf/trk_kf_ch_0.mat in matio's own form (every array deflated in
chunks, here of 4 records), and of the 0.0.21 file above: some 70 kB each,
most of it the chunk indexes' B-tree nodes that libhdf5 allocates whole.

Usage: python3 scripts/make-mat-fixtures.py   (needs h5py)
"""
import os

import h5py
import numpy as np

HERE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "crates", "gsens-gnss-sdr", "tests", "fixtures")
FLOATS = [
    "abs_VE", "abs_E", "abs_P", "abs_L", "abs_VL", "Prompt_I", "Prompt_Q", "acc_carrier_phase_rad",
    "carrier_doppler_hz", "carrier_doppler_rate_hz", "code_freq_chips", "code_freq_rate_chips", "carr_error_hz",
    "carr_error_filt_hz", "code_error_chips", "code_error_filt_chips", "CN0_SNV_dB_Hz", "carrier_lock_test", "aux1",
]
CLASS = {np.float32: b"single", np.float64: b"double", np.uint32: b"uint32", np.uint64: b"uint64", np.int32: b"int32"}


def matlab_header(path):
    header = b"MATLAB 7.3 MAT-file, written by scripts/make-mat-fixtures.py with h5py"
    with open(path, "r+b") as out:
        out.write(header.ljust(116, b" ") + b"\x00" * 8 + b"\x00\x02IM")


def write_matio_like(path, src, n):
    """The first n records of every array, each deflated in chunks of 4 as matio does."""
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with h5py.File(path, "w", userblock_size=512, libver="earliest") as f:
        for name, values in src.items():
            v = values[:n]
            d = f.create_dataset(name, data=v, chunks=(4, 1), compression="gzip", compression_opts=9)
            d.attrs["MATLAB_class"] = np.bytes_(CLASS[v.dtype.type])
    matlab_header(path)


def write(path, src, wn_last, n=None):
    n = n or src["PRN"].shape[0]
    src = {k: v[:n] for k, v in src.items()}
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with h5py.File(path, "w", userblock_size=512, libver="earliest") as f:
        def put(name, values, dtype, **layout):
            d = f.create_dataset(name, data=np.asarray(values, dtype=dtype).reshape(n, 1), **layout)
            d.attrs["MATLAB_class"] = np.bytes_(CLASS[dtype])
        for name in FLOATS:
            put(name, src[name][:, 0], np.float32, chunks=(min(100, n), 1), compression="gzip", compression_opts=9)
        put("PRN_start_sample_count", src["PRN_start_sample_count"][:, 0], np.uint64, chunks=(min(100, n), 1),
            compression="gzip")
        put("aux2", src["aux2"][:, 0], np.float64)
        put("PRN", src["PRN"][:, 0], np.uint32, chunks=(1024, 1), maxshape=(None, 1))
        put("TOW_ms", 345_600_000 + np.arange(n, dtype=np.uint64), np.uint64)
        wn = np.full(n, 2391, dtype=np.int32)
        wn[-1] = wn_last
        dcpl = h5py.h5p.create(h5py.h5p.DATASET_CREATE)
        dcpl.set_layout(h5py.h5d.COMPACT)
        space = h5py.h5s.create_simple((n, 1))
        h5py.h5d.create(f.id, b"WN", h5py.h5t.STD_I32LE, space, dcpl=dcpl).write(
            h5py.h5s.ALL, h5py.h5s.ALL, wn.reshape(n, 1))
        f["WN"].attrs["MATLAB_class"] = np.bytes_(b"int32")
    matlab_header(path)


with h5py.File(os.path.join(HERE, "mat", "trk_ch_0.mat"), "r") as src:
    arrays = {k: src[k][()] for k in src}
write(os.path.join(HERE, "mat-v21", "trk_ch_5.mat"), arrays, 2391)
write(os.path.join(HERE, "mat-v21-wn", "trk_ch_5.mat"), arrays, -1)
SEEDS = os.path.join(HERE, "..", "..", "..", "..", "fuzz", "seeds", "gnss_sdr_mat")
write_matio_like(os.path.join(SEEDS, "v17_8"), arrays, 8)
with h5py.File(os.path.join(HERE, "kf", "trk_kf_ch_0.mat"), "r") as src:
    write_matio_like(os.path.join(SEEDS, "kf_8"), {k: src[k][()] for k in src}, 8)
write(os.path.join(SEEDS, "v21_8"), arrays, 2391, n=8)
# The target's first byte picks the layout: 0, found from the variables.
for seed in ["v17_8", "kf_8", "v21_8"]:
    path = os.path.join(SEEDS, seed)
    with open(path, "rb") as f:
        data = f.read()
    with open(path, "wb") as f:
        f.write(b"\x00" + data)
