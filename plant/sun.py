"""Sun position and the irradiance on a tilted plane from the weather's horizontal beam and diffuse.

Physics in words
----------------
The sun position follows Duffie & Beckman, *Solar Engineering of Thermal Processes* (4th ed.,
§1.6-1.8): declination and equation of time from Spencer's (1971) Fourier series of the day
angle B = 2 pi (n - 1)/365 (n the day of the year, taken fractional so that the geometry is
continuous), solar time = local standard time + 4 min/deg x (longitude - 15 deg E) + equation
of time, hour angle 15 deg per hour from solar noon. The profiles' time axis is local standard
time (CET, no daylight saving; profiles/loaders.py), so `tau` of the step is the standard time.

On a plane of tilt beta and azimuth gamma the irradiance is (isotropic sky, Liu & Jordan):
    G_beam    = E_dir cos(theta) / cos(theta_z)    (beam; E_dir is the horizontal beam)
    G_diffuse = E_dif (1 + cos beta) / 2           (isotropic sky diffuse)
    G_ground  = rho_g (E_dir + E_dif) (1 - cos beta) / 2   (ground reflection, albedo rho_g)
theta is the angle of incidence on the plane, theta_z the zenith angle. cos(theta_z) in the
beam ratio is held at or above cos 85 deg (R_b of a grazing sun is ill-conditioned; D&B §2.14);
beam that falls on the back of the plane or while the computed sun is below the horizon is
dropped (the weather's 15-min means can show a little beam at sunrise and sunset).

Azimuths are given as on the lab's collectors (180 deg = south, 90 = east, 270 = west) and
converted to D&B's convention (0 = south, west positive).

Applicability: a fixed plane, clear of shading; the isotropic model underestimates plane
irradiance on clear days by a few percent against anisotropic models (Hay-Davies, Perez).
Validated by tests/plant/test_sun.py (solstice and equinox noon elevations, the yearly plane
irradiation of Munich 2021 against the horizontal).
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

DAY = 86400.0
YEAR = 365 * DAY
COS_ZENITH_MIN = math.cos(math.radians(85.0))


@njit(cache=True)
def site(latitude, tilt, azimuth):
    """The plane's fixed trigonometry: (sin, cos) of the latitude, of the tilt and of the azimuth
    from south, for latitude/tilt/azimuth [deg]. A plant computes it once per call of its step
    loop, not per step: three of the eight sine-cosine pairs a step's sun took."""
    phi, beta, gamma = math.radians(latitude), math.radians(tilt), math.radians(azimuth - 180.0)
    return (math.sin(phi), math.cos(phi), math.sin(beta), math.cos(beta), math.sin(gamma), math.cos(gamma))


@njit(cache=True)
def position(tau, latitude, longitude):
    """(cos zenith, declination [rad], hour angle [rad]) at local standard time tau [s since
    1 January 00:00 CET], for a site at latitude/longitude [deg, north/east positive]."""
    phi = math.radians(latitude)
    return _position(tau, longitude, math.sin(phi), math.cos(phi))


@njit(cache=True)
def _position(tau, longitude, sp, cp_):
    """position with the latitude's sine and cosine given."""
    tau = tau % YEAR
    B = 2.0 * math.pi * (tau / DAY) / 365.0
    decl = (0.006918 - 0.399912 * math.cos(B) + 0.070257 * math.sin(B) - 0.006758 * math.cos(2 * B)
            + 0.000907 * math.sin(2 * B) - 0.002697 * math.cos(3 * B) + 0.00148 * math.sin(3 * B))
    eot = 229.2 * (0.000075 + 0.001868 * math.cos(B) - 0.032077 * math.sin(B)
                   - 0.014615 * math.cos(2 * B) - 0.04089 * math.sin(2 * B))  # minutes
    minutes = (tau % DAY) / 60.0 + 4.0 * (longitude - 15.0) + eot
    omega = math.radians(15.0 * (minutes / 60.0 - 12.0))
    cos_z = sp * math.sin(decl) + cp_ * math.cos(decl) * math.cos(omega)
    return cos_z, decl, omega


@njit(cache=True)
def incidence(decl, omega, latitude, tilt, azimuth):
    """cos of the angle of incidence on a plane of tilt [deg] and azimuth [deg, 180 = south]."""
    return _incidence(decl, omega, site(latitude, tilt, azimuth))


@njit(cache=True)
def _incidence(decl, omega, g):
    """incidence on the plane of site() g."""
    sp, cp_, sb, cb, sg, cg = g
    sd, cd = math.sin(decl), math.cos(decl)
    co, so = math.cos(omega), math.sin(omega)
    return (sd * sp * cb - sd * cp_ * sb * cg + cd * cp_ * cb * co + cd * sp * sb * cg * co
            + cd * sb * sg * so)


@njit(cache=True)
def plane(tau, E_dir, E_dif, latitude, longitude, tilt, azimuth, albedo):
    """Irradiance on the plane at local standard time tau from the horizontal beam E_dir and
    diffuse E_dif [W/m2]: (beam, diffuse incl. ground reflection, cos incidence) [W/m2, W/m2, 1]."""
    return plane_at(tau, E_dir, E_dif, longitude, albedo, site(latitude, tilt, azimuth))


@njit(cache=True)
def plane_at(tau, E_dir, E_dif, longitude, albedo, g):
    """plane on the plane of site() g (latitude, tilt and azimuth)."""
    cos_z, decl, omega = _position(tau, longitude, g[0], g[1])
    cos_t = _incidence(decl, omega, g)
    beam = 0.0
    if cos_z > 0.0 and cos_t > 0.0 and E_dir > 0.0:
        beam = E_dir * cos_t / max(cos_z, COS_ZENITH_MIN)
    cb = g[3]
    diffuse = max(E_dif, 0.0) * 0.5 * (1.0 + cb) + albedo * (max(E_dir, 0.0) + max(E_dif, 0.0)) * 0.5 * (1.0 - cb)
    return beam, diffuse, max(cos_t, 0.0)


def emit_plane(c, inst, p: str, P) -> tuple[str, str, str]:
    """A kind's irradiance on its plane in the generated step: the plane's site() before the step
    loop (once per call), plane_at in the step's hydraulics, at the step's tau shifted to the
    calendar (calendar_shift). P names the indices of latitude, longitude, tilt, azimuth and
    albedo in the kind's parameters p. -> the locals (beam, diffuse, cos incidence)."""
    shift = c.param(inst, np.array([calendar_shift(getattr(c, "decl", None))]), suffix="_sun")
    smod = c.module(__name__)
    g, beam, dif, cos_t = (c.var(v) for v in ("sun_site", "G_beam", "G_diffuse", "cos_theta"))
    c.header.append(f"{g} = {smod}.site({p}[{P.latitude}], {p}[{P.tilt}], {p}[{P.azimuth}])")
    c.emit("hydraulics", f"{beam}, {dif}, {cos_t} = {smod}.plane_at(tau + {shift}[0], E_dir, E_dif, "
                         f"{p}[{P.longitude}], {p}[{P.albedo}], {g})")
    return beam, dif, cos_t


def calendar_shift(decl) -> float:
    """Seconds to add to the step's `tau` for calendar time: 0 on the year series; in type-day
    mode ([profiles] typeday = k) tau counts from the type-day file start, and block k's middle
    day is a 2021 date (profiles/loaders.py TYPEDAY_BLOCKS; block 11, a cold spell not in 2021,
    is placed on 15 January)."""
    from profiles.loaders import TYPEDAY_BLOCKS, start_offset, typeday_offset

    block = getattr(decl, "typeday", 0) or 0
    if not block:
        return 0.0
    date = TYPEDAY_BLOCKS.get(block, "")
    date = date if date[:4] == "2021" else "2021-01-15"
    return start_offset(date) - DAY - typeday_offset(block)
