r"""
Atomic data of the Ni I 676.78 nm line and of the elements the equation of state needs.

Sources
-------
* **Line** (a¹S₀ → z³P°₁, 3d¹⁰ → 3d⁹(²D)4p): lower level 14 728.847 cm⁻¹
  (1.826 eV), upper 29 500.690 cm⁻¹, log gf = −2.17 (f = 0.0068; the Kurucz
  value carried by RH's and Lightweaver's Ni I model atom, and VALD), radiative
  damping γ_rad = 1.11 × 10⁸ s⁻¹ (same atom file), van der Waals broadening by
  Unsöld's (1955) hydrogenic formula in RH's form (Uitenbroek 2001) with an
  enhancement factor (1 by default, as in that atom file), quadratic Stark
  broadening in RH's approximation.  J = 0 → 1 makes a normal Zeeman triplet;
  g = 1.5 (LS coupling, the value the paper uses); 1.426 is offered as the
  measured alternative.  The rest wavelength is GONG's reference, 676.78 nm
  (air; NIST lists 676.7768 nm air — the 3 pm, 1.4 km/s difference is the
  zero point of the GONG Doppler scale, see `gongsynth.GONGInstrument`).
* **Abundances**: Asplund et al. (2009, ARA&A 47, 481), the set Lightweaver ships.
* **Ionisation energies**: NIST ASD (as tabulated in Kurucz's partition-function file).
* **Partition functions**: Kurucz's tables as distributed with RH and Lightweaver
  (``pf_Kurucz.input``), log₁₀ U sampled here at `PF_TEMPERATURE` and interpolated
  linearly in ln T (largest error against the full table 2500–20 000 K: 0.03 in
  ln U for the species below their caps).  The table sums levels without a
  density cut-off, so a few species diverge with temperature; each is held at its
  value at `PF_CAP` (Al I and K I above 3000 K: their ground-term weights 5.8 and
  2.0, as Irwin 1981 gives for the photosphere; Mg II and Si II above 8000 K).
  Above 20 000 K every partition function is held constant (hydrogen is then
  ionised and the Ni line has no opacity).
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

__all__ = ["ELEMENTS", "ABUNDANCE", "ATOMIC_MASS", "IONISATION_EV", "PF_TEMPERATURE", "PF_CAP",
           "LOG_PARTITION", "partition_function", "LineData", "NiLineData", "FE_I_6173", "LINES",
           "DEFAULT_LINE", "get_line", "zeeman_pattern", "effective_lande", "wigner_3j_squared", "LANDE_LS",
           "LANDE_MEASURED"]

#: Elements of the equation of state (electron donors and the mass budget).
ELEMENTS = ("H", "He", "C", "N", "O", "Na", "Mg", "Al", "Si", "S", "K", "Ca", "Cr", "Fe", "Ni")

#: log ε abundances (log N/N_H + 12), Asplund et al. (2009).
_LOG_EPS = {"H": 12.0, "He": 10.93, "C": 8.43, "N": 7.83, "O": 8.69, "Na": 6.24, "Mg": 7.6, "Al": 6.45,
            "Si": 7.51, "S": 7.12, "K": 5.03, "Ca": 6.34, "Cr": 5.64, "Fe": 7.5, "Ni": 6.22}

#: Number abundance relative to hydrogen.
ABUNDANCE = {el: 10.0 ** (v - 12.0) for el, v in _LOG_EPS.items()}

#: Atomic masses in atomic mass units.
ATOMIC_MASS = {"H": 1.007975, "He": 4.002602, "C": 12.0106, "N": 14.006855, "O": 15.9994,
               "Na": 22.98976928, "Mg": 24.3055, "Al": 26.9815385, "Si": 28.085, "S": 32.0675,
               "K": 39.0983, "Ca": 40.078, "Cr": 51.9961, "Fe": 55.845, "Ni": 58.6934}

#: First ionisation energies (eV).
IONISATION_EV = {"H": 13.5984, "He": 24.5874, "C": 11.2603, "N": 14.5341, "O": 13.6181, "Na": 5.1391,
                 "Mg": 7.6462, "Al": 5.9858, "Si": 8.1517, "S": 10.3599, "K": 4.3407, "Ca": 6.1132,
                 "Cr": 6.7665, "Fe": 7.9024, "Ni": 7.6374}

#: Temperatures (K) of the tabulated partition functions.
PF_TEMPERATURE = np.array([1000, 2000, 2500, 3000, 3500, 4000, 4500, 5000, 5500, 6000, 6500, 7000, 7500,
                           8000, 9000, 10000, 12000, 15000, 20000, 30000, 50000, 100000.])

#: Temperature (K) above which a species' partition function is held constant (see the module notes).
PF_CAP = {"AlI": 3000.0, "KI": 3000.0, "MgII": 8000.0, "SiII": 8000.0}
_PF_TMAX = 20000.0

#: log10 U(T) at `PF_TEMPERATURE` for the neutral (I) and first ion (II) of each element (Kurucz).
LOG_PARTITION = {
    "HI": (0.3010, 0.3010, 0.3010, 0.3010, 0.3010, 0.3010, 0.3010, 0.3010, 0.3010, 0.3010, 0.3010,
            0.3010, 0.3010, 0.3010, 0.3010, 0.3011, 0.3020, 0.3127, 0.4318, 1.0509, 1.8760, 2.5417),
    "HII": (0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000,
            0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000),
    "HeI": (0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000,
            0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0005, 0.0475, 0.7645, 1.9067),
    "HeII": (0.3010, 0.3010, 0.3010, 0.3010, 0.3010, 0.3010, 0.3010, 0.3010, 0.3010, 0.3010, 0.3010,
            0.3010, 0.3010, 0.3010, 0.3010, 0.3010, 0.3010, 0.3010, 0.3010, 0.3010, 0.3023, 0.6676),
    "CI": (0.9359, 0.9452, 0.9476, 0.9499, 0.9527, 0.9558, 0.9594, 0.9634, 0.9677, 0.9721, 0.9767,
            0.9813, 0.9859, 0.9905, 0.9998, 1.0090, 1.0280, 1.0646, 1.1776, 1.5535, 2.1098, 2.6080),
    "CII": (0.7521, 0.7650, 0.7676, 0.7694, 0.7706, 0.7715, 0.7723, 0.7729, 0.7734, 0.7738, 0.7742,
            0.7745, 0.7749, 0.7752, 0.7761, 0.7773, 0.7811, 0.7908, 0.8180, 0.9013, 1.1649, 1.8108),
    "NI": (0.6021, 0.6021, 0.6021, 0.6021, 0.6025, 0.6056, 0.6087, 0.6119, 0.6149, 0.6180, 0.6210,
            0.6276, 0.6350, 0.6423, 0.6565, 0.6758, 0.7160, 0.7887, 0.9807, 1.6060, 2.0873, 2.5145),
    "NII": (0.9140, 0.9267, 0.9322, 0.9358, 0.9385, 0.9404, 0.9420, 0.9432, 0.9463, 0.9497, 0.9531,
            0.9565, 0.9599, 0.9632, 0.9698, 0.9763, 0.9890, 1.0075, 1.0371, 1.1013, 1.5728, 2.3852),
    "OI": (0.9296, 0.9342, 0.9364, 0.9387, 0.9409, 0.9431, 0.9453, 0.9475, 0.9498, 0.9519, 0.9544,
            0.9571, 0.9598, 0.9625, 0.9680, 0.9741, 0.9867, 1.0106, 1.1024, 1.4895, 1.8692, 2.2597),
    "OII": (0.6021, 0.6021, 0.6021, 0.6021, 0.6021, 0.6021, 0.6021, 0.6021, 0.6021, 0.6021, 0.6021,
            0.6021, 0.6021, 0.6050, 0.6194, 0.6333, 0.6599, 0.6971, 0.7647, 0.8924, 1.4607, 2.6540),
    "NaI": (0.3010, 0.3010, 0.3011, 0.3014, 0.3023, 0.3043, 0.3080, 0.3149, 0.3269, 0.3466, 0.3768,
            0.4194, 0.4749, 0.5421, 0.7010, 0.8717, 1.1899, 1.5575, 1.9516, 2.3586, 2.6890, 2.9384),
    "NaII": (0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000,
            0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.1728, 1.8378),
    "MgI": (0.0000, 0.0000, 0.0000, 0.0001, 0.0005, 0.0015, 0.0036, 0.0072, 0.0129, 0.0209, 0.0316,
            0.0454, 0.0627, 0.0840, 0.1403, 0.2167, 0.4230, 0.7788, 1.2676, 1.8332, 2.3142, 2.6860),
    "MgII": (0.3010, 0.3010, 0.3010, 0.3010, 0.3010, 0.3010, 0.3010, 0.3010, 0.3012, 0.3012, 0.3017,
            0.3034, 0.3107, 0.3390, 0.6148, 1.2465, 2.5182, 3.8510, 5.2077, 6.6027, 7.7795, 8.7631),
    "AlI": (0.7327, 0.7551, 0.7597, 0.7633, 0.7820, 0.9485, 1.4560, 2.0817, 2.6454, 3.1267, 3.5384,
            3.8935, 4.2032, 4.4756, 4.9329, 5.3026, 5.8647, 6.4401, 7.0367, 7.6715, 8.2402, 8.7676),
    "AlII": (0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0009, 0.0022, 0.0034, 0.0044,
            0.0054, 0.0067, 0.0079, 0.0133, 0.0237, 0.0431, 0.1066, 0.3226, 1.1442, 2.0219, 2.5371),
    "SiI": (0.8640, 0.9112, 0.9243, 0.9359, 0.9467, 0.9569, 0.9665, 0.9755, 0.9840, 0.9920, 0.9996,
            1.0068, 1.0138, 1.0207, 1.0350, 1.0511, 1.0952, 1.2039, 1.4592, 1.9024, 2.3489, 2.7099),
    "SiII": (0.6671, 0.7204, 0.7316, 0.7392, 0.7446, 0.7487, 0.7519, 0.7545, 0.7567, 0.7584, 0.7600,
            0.7614, 0.7630, 0.7657, 0.7943, 0.9674, 1.9923, 3.4115, 4.8775, 6.3825, 7.6474, 8.6970),
    "SI": (0.8856, 0.9021, 0.9102, 0.9180, 0.9258, 0.9334, 0.9409, 0.9479, 0.9545, 0.9611, 0.9676,
            0.9735, 0.9794, 0.9851, 0.9963, 1.0073, 1.0352, 1.1219, 1.4060, 1.7675, 2.0959, 2.4625),
    "SII": (0.6021, 0.6021, 0.6021, 0.6021, 0.6021, 0.6021, 0.6021, 0.6079, 0.6223, 0.6365, 0.6501,
            0.6633, 0.6761, 0.6886, 0.7124, 0.7351, 0.7813, 0.8449, 0.9342, 1.1198, 1.5084, 1.9099),
    "KI": (0.3010, 0.3013, 0.3297, 0.8026, 1.7431, 2.5541, 3.1982, 3.7183, 4.1471, 4.5068, 4.8133,
            5.0777, 5.3086, 5.5119, 5.8541, 6.1317, 6.5556, 6.9928, 7.4512, 7.9479, 8.4060, 8.8505),
    "KII": (0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000,
            0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0005, 0.1027, 1.3688, 2.4937),
    "CaI": (0.0000, 0.0000, 0.0009, 0.0029, 0.0091, 0.0210, 0.0409, 0.0686, 0.1066, 0.1520, 0.2046,
            0.2644, 0.3305, 0.4020, 0.5543, 0.7058, 1.0082, 1.3645, 1.7652, 2.2063, 2.5709, 2.8510),
    "CaII": (0.3012, 0.3012, 0.3019, 0.3042, 0.3088, 0.3168, 0.3280, 0.3423, 0.3594, 0.3785, 0.3992,
            0.4206, 0.4427, 0.4652, 0.5094, 0.5516, 0.6313, 0.7391, 0.9164, 1.2975, 1.8090, 2.2858),
    "CrI": (0.8182, 0.8507, 0.8635, 0.8839, 0.9109, 0.9426, 0.9782, 1.0167, 1.0590, 1.1038, 1.1511,
            1.2009, 1.2530, 1.3071, 1.4180, 1.5266, 1.7417, 2.0085, 2.3292, 2.7066, 3.0367, 3.2993),
    "CrII": (0.7739, 0.7783, 0.7800, 0.7845, 0.7932, 0.8070, 0.8267, 0.8518, 0.8828, 0.9179, 0.9565,
            0.9979, 1.0414, 1.0865, 1.1780, 1.2668, 1.4394, 1.6586, 1.9489, 2.4038, 2.9816, 3.5667),
    "FeI": (1.1939, 1.2889, 1.3165, 1.3415, 1.3662, 1.3912, 1.4171, 1.4439, 1.4725, 1.5021, 1.5329,
            1.5651, 1.5986, 1.6335, 1.7069, 1.7824, 1.9482, 2.1895, 2.5270, 2.9710, 3.3762, 3.7029),
    "FeII": (1.2563, 1.4496, 1.4978, 1.5355, 1.5663, 1.5928, 1.6162, 1.6376, 1.6580, 1.6774, 1.6963,
            1.7150, 1.7335, 1.7520, 1.7890, 1.8254, 1.8993, 2.0052, 2.1721, 2.4981, 2.9911, 3.5289),
    "NiI": (1.2170, 1.3560, 1.3929, 1.4208, 1.4429, 1.4610, 1.4763, 1.4897, 1.5021, 1.5137, 1.5251,
            1.5367, 1.5487, 1.5616, 1.5908, 1.6248, 1.7178, 1.8941, 2.1971, 2.6409, 3.0564, 3.3915),
    "NiII": (0.7860, 0.8686, 0.8937, 0.9191, 0.9460, 0.9745, 1.0041, 1.0339, 1.0637, 1.0927, 1.1208,
            1.1478, 1.1738, 1.1987, 1.2454, 1.2878, 1.3646, 1.4635, 1.6129, 1.9589, 2.5960, 3.2988),
}


def partition_function(species, temperature):
    """
    Partition function U(T) of a species from the Kurucz table.

    Parameters
    ----------
    species : str
        Element and stage, e.g. ``"NiI"``, ``"FeII"``.
    temperature : float or `numpy.ndarray`
        Temperature in K.

    Returns
    -------
    float or `numpy.ndarray`
        U (dimensionless).

    Examples
    --------
    >>> round(float(partition_function("HI", 5000.0)), 3)
    2.0
    >>> round(float(partition_function("NiI", 5000.0)), 1)
    30.9
    """
    t = np.minimum(np.asarray(temperature, dtype=np.float64), PF_CAP.get(species, _PF_TMAX))
    t = np.clip(t, PF_TEMPERATURE[0], None)
    log_u = np.interp(np.log(t), np.log(PF_TEMPERATURE), np.asarray(LOG_PARTITION[species]))
    return 10.0 ** log_u


#: Landé factor of Ni I z³P°₁ in LS coupling (the paper's value, and GONG's reduction constant).
LANDE_LS = 1.5
#: Measured Landé factor of Ni I z³P°₁, the line's effective factor (Bruls 1993, A&A 269, 509;
#: DESIGN §3.20).
LANDE_MEASURED = 1.426

_CM_TO_EV = 1.239841984e-4
_FIELD_NAMES_TEXT = ("name", "element")


def wigner_3j_squared(j1, j2, j3, m1, m2, m3):
    """
    Square of the Wigner 3-j symbol (j1 j2 j3; m1 m2 m3) by Racah's formula.

    Parameters
    ----------
    j1, j2, j3, m1, m2, m3 : float
        Integer or half-integer angular momenta and projections.

    Returns
    -------
    float

    Examples
    --------
    >>> round(wigner_3j_squared(1, 0, 1, 0, 0, 0), 6)     # 1/3
    0.333333
    """
    from math import factorial

    if abs(m1 + m2 + m3) > 1e-9 or any(abs(m) > j + 1e-9 for m, j in ((m1, j1), (m2, j2), (m3, j3))):
        return 0.0
    if not abs(j1 - j2) - 1e-9 <= j3 <= j1 + j2 + 1e-9:
        return 0.0

    def f(x):
        return factorial(int(round(x)))

    tri = f(j1 + j2 - j3) * f(j1 - j2 + j3) * f(-j1 + j2 + j3) / f(j1 + j2 + j3 + 1)
    pre = tri * f(j1 + m1) * f(j1 - m1) * f(j2 + m2) * f(j2 - m2) * f(j3 + m3) * f(j3 - m3)
    total = 0.0
    for k in range(0, int(round(j1 + j2 + j3)) + 1):
        args = (k, j1 + j2 - j3 - k, j1 - m1 - k, j2 + m2 - k, j3 - j2 + m1 + k, j3 - j1 - m2 + k)
        if min(args) < -1e-9:
            continue
        total += (-1) ** k / np.prod([f(a) for a in args])
    return float(pre * total * total)


def zeeman_pattern(j_lower, j_upper, lande_lower, lande_upper):
    """
    Zeeman components of a J_l → J_u dipole transition in the linear (weak-field) regime.

    Parameters
    ----------
    j_lower, j_upper : float
        Total angular momenta of the levels (|ΔJ| ≤ 1, not 0 → 0).
    lande_lower, lande_upper : float
        Their Landé factors (a J = 0 level's is irrelevant).

    Returns
    -------
    dict
        For q = M_l − M_u in (−1, 0, +1): a list of ``(shift, strength)``: the
        wavelength shift in units of Δλ_B = 4.67e-13 λ²[Å] B[G] Å,
        g_l M_l − g_u M_u, and the relative strength 3 (J_u J_l 1; −M_u M_l −q)²,
        which sums to 1 over each q (Landi Degl'Innocenti & Landolfi 2004, §3.1).

    Examples
    --------
    >>> p = zeeman_pattern(0, 1, 0.0, 1.5)                # a normal triplet
    >>> p[1], p[0], p[-1]
    ([(1.5, 1.0)], [(0.0, 1.0)], [(-1.5, 1.0)])
    """
    if abs(j_upper - j_lower) > 1 or (j_upper == 0 and j_lower == 0):
        raise ValueError(f"not a dipole transition: J_l = {j_lower}, J_u = {j_upper}")
    pattern = {}
    for q in (-1, 0, 1):
        comps = []
        for k in range(int(round(2 * j_lower)) + 1):
            m_l = -j_lower + k
            m_u = m_l - q
            if abs(m_u) > j_upper + 1e-9:
                continue
            s = 3.0 * wigner_3j_squared(j_upper, j_lower, 1, -m_u, m_l, -q)
            if s > 0:
                comps.append((float(lande_lower * m_l - lande_upper * m_u) + 0.0, round(s, 12)))
        pattern[q] = comps
    return pattern


def effective_lande(j_lower, j_upper, lande_lower, lande_upper):
    """
    Effective Landé factor ḡ = ½(g_u + g_l) + ¼(g_u − g_l)[J_u(J_u+1) − J_l(J_l+1)].

    The centre of gravity of the σ components of `zeeman_pattern` in units of Δλ_B
    (Landi Degl'Innocenti & Landolfi 2004, eq. 3.44); it sets the weak-field V.

    Parameters
    ----------
    j_lower, j_upper, lande_lower, lande_upper : float

    Returns
    -------
    float

    Examples
    --------
    >>> effective_lande(1, 0, 2.5, 0.0)                    # Fe I 617.3 nm
    2.5
    """
    d = j_upper * (j_upper + 1) - j_lower * (j_lower + 1)
    return 0.5 * (lande_upper + lande_lower) + 0.25 * (lande_upper - lande_lower) * d


@dataclass(frozen=True)
class LineData:
    """
    Atomic data of one spectral line for LTE Zeeman synthesis (cgs and eV).

    Every instance in `LINES` cites its sources in its notes; see `NiLineData`
    and `FE_I_6173` for the two lines gongsynth ships.

    Zeeman pattern: the levels' J and Landé factors give the full pattern
    (`zeeman_pattern`) and its effective Landé factor (`effective_lande`).  The
    transfer uses a triplet with ``lande`` (the ``lande_g`` given, else the
    levels' effective factor): exact for the normal triplets of J = 0 ↔ 1
    (both shipped lines), and for an anomalous pattern the effective-triplet
    approximation, which keeps the weak-field V (∝ ḡ) exact and misses the
    second-order splitting of Q and U (`is_normal_triplet` says which).

    Parameters
    ----------
    name : str
        Registry name, e.g. ``"Ni I 676.8"``.
    element : str
        Element symbol of a neutral atom of the equation of state (`ELEMENTS`).
    wavelength_nm : float
        Rest wavelength in air (nm), the zero of the line's Doppler scale.
    log_gf : float
        log10 (g_l f).
    lower_energy_cm, upper_energy_cm : float
        Level energies (cm⁻¹).
    ion_ground_cm : float
        Ionisation energy (cm⁻¹, the ion's ground level): the continuum of the
        Unsöld and Stark formulas.
    j_lower, j_upper : float
        Total angular momenta of the levels.
    lande_lower, lande_upper : float
        Their Landé factors (measured where known).
    gamma_rad : float
        Radiative damping (s⁻¹).
    lande_g : float or None
        Effective Landé factor of the synthesis; None (default) takes the
        levels' (`effective_lande`).
    vdw_sigma, vdw_alpha : float or None
        Anstee–Barklem–O'Mara cross-section (a₀², at 10 km/s) and velocity
        exponent; None: Unsöld's formula times ``vdw_enhancement``.
    vdw_enhancement : float
        Factor on Unsöld's van der Waals width (1.0; unused with ABO data).
    stark_enhancement : float
        Factor on the quadratic Stark width (1.0).
    mass_amu : float or None
        Atomic mass (default the element's, `ATOMIC_MASS`).
    partition_levels : tuple or None
        Optional explicit levels ``((E_cm, g, stage), ...)`` for the element's
        partition functions instead of the Kurucz table (to reproduce a model
        atom, e.g. Lightweaver's, in a comparison).
    """

    name: str
    element: str
    wavelength_nm: float
    log_gf: float
    lower_energy_cm: float
    upper_energy_cm: float
    ion_ground_cm: float
    j_lower: float
    j_upper: float
    lande_lower: float
    lande_upper: float
    gamma_rad: float
    lande_g: float | None = None
    vdw_sigma: float | None = None
    vdw_alpha: float | None = None
    vdw_enhancement: float = 1.0
    stark_enhancement: float = 1.0
    mass_amu: float | None = None
    partition_levels: tuple | None = None

    def __post_init__(self):
        cls = type(self).__name__
        for name in _FIELD_NAMES_TEXT:
            if not isinstance(getattr(self, name), str):
                raise TypeError(f"{cls}.{name} must be a str, got {getattr(self, name)!r}")
        if self.element not in ELEMENTS:
            raise ValueError(f"{cls}.element must be one of {ELEMENTS}, got {self.element!r}")
        if self.mass_amu is None:
            object.__setattr__(self, "mass_amu", ATOMIC_MASS[self.element])
        optional = ("lande_g", "vdw_sigma", "vdw_alpha")
        for f in dataclasses.fields(self):
            value = getattr(self, f.name)
            if f.name in _FIELD_NAMES_TEXT + ("partition_levels",) or (f.name in optional and value is None):
                continue
            if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)) \
                    or not np.isfinite(value):
                raise ValueError(f"{cls}.{f.name} must be a finite number, got {value!r}")
        for name in ("wavelength_nm", "gamma_rad", "mass_amu", "ion_ground_cm"):
            if getattr(self, name) <= 0:
                raise ValueError(f"{cls}.{name} must be positive, got {getattr(self, name)!r}")
        for name in ("vdw_enhancement", "stark_enhancement", "j_lower", "j_upper"):
            if getattr(self, name) < 0:
                raise ValueError(f"{cls}.{name} must be >= 0, got {getattr(self, name)!r}")
        for name in ("j_lower", "j_upper"):
            if abs(2 * getattr(self, name) - round(2 * getattr(self, name))) > 1e-9:
                raise ValueError(f"{cls}.{name} must be an integer or half-integer, "
                                 f"got {getattr(self, name)!r}")
        if abs(self.j_upper - self.j_lower) > 1 or self.j_upper == self.j_lower == 0:
            raise ValueError(f"{cls}: J_l = {self.j_lower} → J_u = {self.j_upper} is not a dipole transition")
        if (self.vdw_sigma is None) != (self.vdw_alpha is None):
            raise ValueError(f"{cls}.vdw_sigma and vdw_alpha go together (ABO data), got "
                             f"{self.vdw_sigma!r} and {self.vdw_alpha!r}")
        if self.vdw_sigma is not None and (self.vdw_sigma <= 0 or not 0 <= self.vdw_alpha < 1):
            raise ValueError(f"{cls}: ABO sigma must be > 0 and alpha in [0, 1), got "
                             f"{self.vdw_sigma!r}, {self.vdw_alpha!r}")
        if not self.lower_energy_cm < self.upper_energy_cm < self.ion_ground_cm:
            raise ValueError(f"{cls}: need lower_energy_cm < upper_energy_cm < ion_ground_cm, got "
                             f"{self.lower_energy_cm}, {self.upper_energy_cm}, {self.ion_ground_cm}")

    @property
    def g_lower(self):
        """Statistical weight of the lower level, 2 J_l + 1."""
        return int(round(2 * self.j_lower + 1))

    @property
    def oscillator_strength(self):
        """Absorption oscillator strength f = gf / g_lower."""
        return 10.0 ** self.log_gf / self.g_lower

    @property
    def lower_energy_ev(self):
        """Lower-level excitation energy (eV)."""
        return self.lower_energy_cm * _CM_TO_EV

    @property
    def ionisation_ev(self):
        """Ionisation energy of the neutral atom (eV), from ``ion_ground_cm``."""
        return self.ion_ground_cm * _CM_TO_EV

    @property
    def zeeman(self):
        """The levels' Zeeman pattern (`zeeman_pattern`)."""
        return zeeman_pattern(self.j_lower, self.j_upper, self.lande_lower, self.lande_upper)

    @property
    def is_normal_triplet(self):
        """Whether the levels' pattern is a triplet (one shift per q): exact in the transfer."""
        return all(len({shift for shift, _ in c}) == 1 for c in self.zeeman.values())

    @property
    def lande(self):
        """Effective Landé factor used by the synthesis: ``lande_g``, else the levels' `effective_lande`."""
        if self.lande_g is not None:
            return float(self.lande_g)
        return float(effective_lande(self.j_lower, self.j_upper, self.lande_lower, self.lande_upper))

    def partition_functions(self, temperature):
        """
        U of the neutral atom and of the first ion at ``temperature`` (K).

        Parameters
        ----------
        temperature : `numpy.ndarray`
            Temperatures in K.

        Returns
        -------
        (`numpy.ndarray`, `numpy.ndarray`)
            The neutral and ion partition functions.
        """
        t = np.asarray(temperature, dtype=np.float64)
        if self.partition_levels is None:
            return partition_function(f"{self.element}I", t), partition_function(f"{self.element}II", t)
        u = [np.zeros_like(t), np.zeros_like(t)]
        ground = [min(e for e, _, s in self.partition_levels if s == k) for k in (0, 1)]
        for energy, weight, stage in self.partition_levels:
            if stage in (0, 1):
                u[stage] = u[stage] + weight * np.exp(-1.4387769 * (energy - ground[stage]) / t)
        return u[0], u[1]

    def replace(self, **changes):
        """
        A copy with some fields changed.

        Parameters
        ----------
        **changes
            Field names and new values.

        Returns
        -------
        `LineData`
            Of the same class.
        """
        return dataclasses.replace(self, **changes)


@dataclass(frozen=True)
class NiLineData(LineData):
    """
    Ni I 676.78 nm (a¹S₀ → z³P°₁, 3d¹⁰ → 3d⁹(²D)4p), GONG's line.

    Sources: lower level 14 728.847 cm⁻¹ (1.826 eV), upper 29 500.690 cm⁻¹,
    Ni II ground 61 579 cm⁻¹ (the series limit Barklem et al. 2000 list for
    this upper level; NIST's ionisation energy is 61 619.8 cm⁻¹), log gf = −2.17 (f = 0.0068; the Kurucz value
    carried by RH's and Lightweaver's Ni I model atom, and VALD), γ_rad =
    1.11 × 10⁸ s⁻¹ (same atom file); van der Waals broadening by Unsöld's
    (1955) formula in RH's form (Uitenbroek 2001), enhancement 1 as in that
    atom file (the line is not in Barklem et al. 2000's ABO list);
    quadratic Stark broadening in RH's approximation.  J = 0 → 1: a normal
    Zeeman triplet with ḡ = g(z³P°₁); the Sun's value is the measured
    1.426 (`LANDE_MEASURED`, Bruls 1993, A&A 269, 509, "The formation of
    helioseismology lines IV: the Ni I 676.8 nm intercombination line"; DESIGN §3.20),
    LS coupling gives 1.5 (`LANDE_LS`, the paper's value and GONG's
    reduction constant): ``NiLineData(lande_g=LANDE_LS)``.  The rest
    wavelength is GONG's reference, 676.78 nm (air; NIST lists 676.7768 nm
    air — the 3 pm, 1.4 km/s difference is the zero point of the GONG Doppler
    scale, see `gongsynth.GONGInstrument`).

    Parameters
    ----------
    **fields
        Any field of `LineData` (defaults: the values above).

    Examples
    --------
    >>> line = NiLineData()
    >>> round(line.lower_energy_ev, 3), round(line.oscillator_strength, 4), line.lande
    (1.826, 0.0068, 1.426)
    """

    name: str = "Ni I 676.8"
    element: str = "Ni"
    wavelength_nm: float = 676.78
    log_gf: float = -2.17
    lower_energy_cm: float = 14728.847
    upper_energy_cm: float = 29500.690
    ion_ground_cm: float = 61579.0
    j_lower: float = 0
    j_upper: float = 1
    lande_lower: float = 0.0
    lande_upper: float = LANDE_MEASURED
    gamma_rad: float = 1.11e8


#: Fe I 617.33 nm, HMI's line (a⁵P₁ → y⁵D°₀, 3d⁷(⁴F)4s → 3d⁶(⁵D)4s4p).
#:
#: Sources: air wavelength 617.33433 nm, the rest wavelength of HMI's pipeline
#: and filter tuning (``lam0 = 6173.3433`` Å; Schou et al. 2012, Couvidat et
#: al. 2012; Nave et al. 1994 measure 6173.3344 Å in the laboratory: the
#: 0.43 km/s difference is HMI's Doppler zero point, as GONG's 676.78 nm is for
#: Ni); levels 17 927.377 and 34 121.578 cm⁻¹ (2.223 eV; Nave et al. 1994 as
#: listed by Barklem, Piskunov & O'Mara 2000, A&AS 142, 467), Fe II ground
#: 63 737 cm⁻¹ (7.9024 eV, NIST ASD); log gf = −2.880 (VALD; Nave et al.
#: 1994, the value Norton et al. 2006, Sol. Phys. 239, 69 use); J = 1 → 0:
#: a normal triplet with ḡ = g(a⁵P₁) = 2.5 (LS coupling; the value Norton et al.
#: 2006 and HMI's reduction use); van der Waals broadening by hydrogen from ABO
#: theory, σ = 281 a₀², α = 0.266 (Barklem, Piskunov & O'Mara 2000), helium
#: added as 0.42 n_He (Barklem's recipe); γ_rad = 10^8.31 s⁻¹ (log Γ_rad = 8.31,
#: the VALD/Kurucz value of spectral-line lists for this line: not checked here
#: against VALD itself; a factor 2 on it moves the disk-centre depth by < 0.2 %
#: of I_c, ``tests/test_rt_lines.py``); quadratic Stark broadening in RH's approximation,
#: as for Ni.
FE_I_6173 = LineData(name="Fe I 617.3", element="Fe", wavelength_nm=617.33433, log_gf=-2.880,
                     lower_energy_cm=17927.377, upper_energy_cm=34121.578, ion_ground_cm=63737.0,
                     j_lower=1, j_upper=0, lande_lower=2.5, lande_upper=0.0, gamma_rad=10 ** 8.31,
                     vdw_sigma=281.0, vdw_alpha=0.266)

#: The lines gongsynth synthesises, by name (the first is the default).
LINES = {"Ni I 676.8": NiLineData(), "Fe I 617.3": FE_I_6173}

#: Name of the default line.
DEFAULT_LINE = "Ni I 676.8"


def get_line(line=None):
    """
    The `LineData` of a name in `LINES` (or a `LineData` itself).

    Parameters
    ----------
    line : str, `LineData` or None
        A key of `LINES` (e.g. ``"Fe I 617.3"``), a `LineData`, or None for
        `DEFAULT_LINE`.

    Returns
    -------
    `LineData`

    Examples
    --------
    >>> get_line("Fe I 617.3").lande, get_line().wavelength_nm
    (2.5, 676.78)
    """
    if line is None:
        return LINES[DEFAULT_LINE]
    if isinstance(line, LineData):
        return line
    if isinstance(line, str):
        if line not in LINES:
            raise ValueError(f"line must be one of {tuple(LINES)} or a LineData, got {line!r}")
        return LINES[line]
    raise TypeError(f"line must be a line name {tuple(LINES)}, a LineData or None, got {type(line).__name__}")
