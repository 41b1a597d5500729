"""gsens.Loop against independent values: the textbook loop coefficients
(Kaplan & Hegarty, Understanding GPS, Table 5.6), scipy.signal's frequency
responses and filters of the loops' transfer functions, and the noise
bandwidth's defining integral."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import integrate, optimize, signal

import gsens

TWO_PI = 2 * np.pi
F_HZ = np.geomspace(0.01, 20.0, 400)


def textbook_coefficients(order, bn_hz, zeta=1 / np.sqrt(2), a3=1.1, b3=2.4):
    """c0, c1, c2 of the loop filter from Bn (Kaplan & Hegarty, Table 5.6)."""
    if order == 2:
        wn = 8 * zeta * bn_hz / (4 * zeta**2 + 1)
        return 2 * zeta * wn, wn**2, 0.0
    # The 3rd-order loop's Bn/ωn = 0.7845 for a3 = 1.1, b3 = 2.4 (Table 5.6).
    wn = bn_hz / 0.7845
    return b3 * wn, a3 * wn**2, wn**3


def continuous_tf(order, c):
    """L(s) = −2π·s^(n−1) / (s^n + c0·s^(n−1) + c1·s^(n−2) + c2·s^(n−3)):
    the phase error [rad] per Hz of oscillator frequency error (docs/conventions.md)."""
    if order == 2:
        return [-TWO_PI, 0.0], [1.0, c[0], c[1]]
    return [-TWO_PI, 0.0, 0.0], [1.0, c[0], c[1], c[2]]


@pytest.mark.parametrize("bn_hz", [1.0, 3.0, 10.0])
@pytest.mark.parametrize("zeta", [0.5, 1 / np.sqrt(2), 1.0])
def test_second_order_coefficients_response_and_peak(bn_hz, zeta):
    loop = gsens.Loop(order=2, bn_hz=bn_hz, zeta=zeta)
    c = textbook_coefficients(2, bn_hz, zeta)
    np.testing.assert_allclose(loop.coefficients(), c, rtol=1e-12, atol=1e-12)
    b, a = continuous_tf(2, c)
    _, h = signal.freqs(b, a, worN=TWO_PI * F_HZ)
    np.testing.assert_allclose(loop.response(F_HZ), h, rtol=1e-10)
    # The 2nd-order loop's |L| peaks at ωn with 2π/c0.
    f_peak, gain = loop.peak()
    assert f_peak == pytest.approx(np.sqrt(c[1]) / TWO_PI, rel=1e-6)
    assert gain == pytest.approx(TWO_PI / c[0], rel=1e-9)
    assert loop.natural_frequency_hz == pytest.approx(np.sqrt(c[1]) / TWO_PI, rel=1e-12)


@pytest.mark.parametrize("order", [2, 3])
def test_half_power_band_and_noise_bandwidth(order):
    loop = gsens.Loop(order=order, bn_hz=3.0)
    # The loop's own c (checked against the textbook's above and below).
    b, a = continuous_tf(order, loop.coefficients())
    mag = lambda f: abs(signal.freqs(b, a, worN=[TWO_PI * f])[1][0])  # noqa: E731
    f_peak = optimize.minimize_scalar(lambda f: -mag(f), bounds=(0.05, 5.0), method="bounded", options={"xatol": 1e-9}).x
    assert loop.peak()[0] == pytest.approx(f_peak, rel=1e-4)
    assert loop.peak()[1] == pytest.approx(mag(f_peak), rel=1e-9)
    half = mag(f_peak) / np.sqrt(2)
    lo = optimize.brentq(lambda f: mag(f) - half, 1e-3, f_peak, xtol=1e-12)
    hi = optimize.brentq(lambda f: mag(f) - half, f_peak, 100.0, xtol=1e-12)
    np.testing.assert_allclose(loop.half_power_band_hz(), (lo, hi), rtol=1e-6)
    # Bn = ∫₀^∞ |H(j2πf)|² df with H = 1 − s·L(s)/(−2π) the closed loop's phase transfer.
    c = loop.coefficients()
    num = [c[0], c[1]] if order == 2 else [c[0], c[1], c[2]]
    den = [1.0, c[0], c[1]] if order == 2 else [1.0, c[0], c[1], c[2]]
    h2 = lambda f: abs(signal.freqs(num, den, worN=[TWO_PI * f])[1][0]) ** 2  # noqa: E731
    bn = integrate.quad(h2, 0, np.inf, limit=400, epsabs=1e-12)[0]
    # The 3rd-order row of Table 5.6 rounds Bn/ωn to 4 digits.
    assert bn == pytest.approx(3.0, rel=1e-9 if order == 2 else 2e-4)


def test_third_order_coefficients_and_response():
    loop = gsens.Loop(order=3, bn_hz=5.0)
    c = textbook_coefficients(3, 5.0)
    np.testing.assert_allclose(loop.coefficients(), c, rtol=2e-4)
    b, a = continuous_tf(3, loop.coefficients())
    _, h = signal.freqs(b, a, worN=TWO_PI * F_HZ)
    np.testing.assert_allclose(loop.response(F_HZ), h, rtol=1e-10)


def discrete_response(loop, f_hz):
    """L_d(e^{j2πfT}) evaluated from the formula directly (no polynomial
    expansion, which loses digits near z = 1)."""
    t = loop.interval_s
    c0, c1, c2 = loop.coefficients()
    z = np.exp(1j * TWO_PI * f_hz * t)
    g = np.pi * t * (z + 1) / (z - 1)
    acc = 1 / (1 - 1 / z)
    f_d = c0 + c1 * t * acc + c2 * t**2 * acc**2
    return -g / (1 + g * f_d / (z * TWO_PI))


def discrete_tf(loop):
    """L_d(z) = −G/(1 + G·z⁻¹·F_d/2π), G = πT(z+1)/(z−1),
    F_d = c0 + c1·T/(1−z⁻¹) + c2·T²/(1−z⁻¹)² (gsens_core::DiscretePll's
    documented recursion), as polynomials in z over z(z−1)³."""
    t = loop.interval_s
    c0, c1, c2 = loop.coefficients()
    P = np.polynomial.polynomial  # ascending powers of z
    zm1 = [-1.0, 1.0]
    zp1 = [1.0, 1.0]
    z = [0.0, 1.0]
    n = P.polyadd(P.polyadd(c0 * P.polypow(zm1, 2), c1 * t * P.polymul(z, zm1)), c2 * t**2 * P.polypow(z, 2))
    num = -np.pi * t * P.polymul(P.polymul(zp1, z), P.polypow(zm1, 2))
    den = P.polyadd(P.polymul(z, P.polypow(zm1, 3)), 0.5 * t * P.polymul(zp1, n))
    # Descending powers of z = ascending powers of z⁻¹ (both of degree 4).
    return num[::-1], den[::-1]


@pytest.mark.parametrize("order,bn_hz,interval_s", [(2, 3.0, 0.001), (2, 15.0, 0.02), (3, 10.0, 0.005)])
def test_discrete_loop_response_and_filter_against_scipy(order, bn_hz, interval_s):
    loop = gsens.Loop(order=order, bn_hz=bn_hz, interval_s=interval_s)
    b, a = discrete_tf(loop)
    f = F_HZ[F_HZ < 0.5 / interval_s]
    np.testing.assert_allclose(loop.response(f), discrete_response(loop, f), rtol=1e-9)
    # The expanded polynomials carry (z−1)³: at f·T ~ 1e-5 they keep ~7 digits.
    _, h = signal.freqz(b, a, worN=f, fs=1 / interval_s)
    np.testing.assert_allclose(loop.response(f), h, rtol=1e-6)
    delta_f_hz = np.random.default_rng(11).normal(0.0, 0.5, 5000)
    reference = signal.lfilter(b, a, delta_f_hz)
    np.testing.assert_allclose(loop.filter(delta_f_hz), reference, rtol=0, atol=1e-9 * np.abs(reference).max())


def test_a_constant_frequency_error_is_rejected():
    loop = gsens.Loop(order=2, bn_hz=3.0, interval_s=0.001)
    phase = loop.filter(np.full(20000, 2.0))
    assert phase[0] == pytest.approx(-np.pi * 0.001 * 2.0)
    assert abs(phase[-1]) < 1e-9


def test_bad_loops_are_refused():
    with pytest.raises(gsens.GsensError):
        gsens.Loop(order=4, bn_hz=3)
    with pytest.raises(gsens.GsensError):
        gsens.Loop(order=2, bn_hz=-1)
    with pytest.raises(gsens.GsensError, match="discrete"):
        gsens.Loop(order=2, bn_hz=3).filter(np.ones(3))
