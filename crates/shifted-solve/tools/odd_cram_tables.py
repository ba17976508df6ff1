#!/usr/bin/env python3
"""Odd-degree CRAM tables for shifted-solve (degrees 3, 5, 7).

Exact command used to produce the constants in src/poles.rs:

    python3 crates/shifted-solve/tools/odd_cram_tables.py

(needs only `mpmath`, e.g. `pip install mpmath`; runs in about a second.)

Provenance of the input: the best uniform rational approximation r_n = p/q of exp(-x) on
[0, inf) computed by transmutagen's 200-digit Remez algorithm (ergs/transmutagen,
`transmutagen/data/CRAM_cache/{n}_200`, commit 718c5588), coefficients truncated here to 45
significant digits. This script does NOT trust that input: it

1. finds the poles (roots of q) and residues c_k = p(z_k)/q'(z_k) at 60 digits,
2. verifies the equioscillation property that characterises the best approximation
   (Chebyshev's theorem): the error e(x) = r(x) - exp(-x) must have 2n+2 alternating
   extrema of equal magnitude E_n on [0, inf], counting x = 0 and x = inf,
3. checks that E_n equals |c0| = |r(inf)| and matches the table in NUMERICS.md §2.2,
4. prints the table in the x-plane convention of the crate:
   exp(-x) ~ c0 + 2 Re sum_{Im z_j > 0} c_j/(x - z_j) + c_r/(x - z_r)  (z_r < 0 real).
"""
import mpmath as mp

mp.mp.dps = 60

# Ascending-power coefficients of numerator and denominator (denominator constant = 1).
TABLES = {
    3: (
        ["1.00079938063633568782880811900971119616897657",
         "-0.223657427183518877868829199355981451136940186",
         "0.0124996015453989844345093666484857888388843639",
         "-0.0000998100158985782818540562927411535765648842067"],
        ["1",
         "0.798293570897522133290437596685254205556628655",
         "0.220409711615114896260804271937842157242894349",
         "0.124859186427258631588295917415848510535928405"],
    ),
    5: (
        ["1.00000934571315302664647675365682079239798961",
         "-0.250231007064181117452619660684137842182998247",
         "0.0224806133069652128760269163605435926258788840",
         "-0.000833630857342390593332011378703150905387749601",
         "0.0000107798106790925613831881737307549506499568312",
         "-0.0000000219126974691865704983907735559763109642518"],
        ["1",
         "0.750174436295088264842408525766008595547590299",
         "0.269910131344176748968464994130288760272371445",
         "0.0676686260415665871015897498624124858927627472",
         "0.00693461355600321244085075279059450185840749937",
         "0.00234467901062104137358167779654694485911643470"],
    ),
    7: (
        ["1.00000010874974913752479608665313072729334785",
         "-0.261398902451573253737973118806055529065174855",
         "0.0275487372365122333527605617849769546089462615",
         "-0.00146757436754436540438720197441592575534158960",
         "0.0000406048852702560075979921949445376764880206034",
         "-0.000000537058914183357540848423728901995865741234092",
         "0.00000000265386778169358897172006532449274263637987",
         "-0.00000000000211890283160797028427592768673424288775035"],
        ["1",
         "0.738607552654036520733182639502490449830366087",
         "0.266095421673315716989500185519665081991072114",
         "0.0622103805406815052246549040005179606458715099",
         "0.0102296330365184003655291514126981974915166854",
         "0.00148788178197519089085889285365404865601035191",
         "0.0000808839142334073397653214684268097718091746317",
         "0.0000194842089146192735247891282523605524908716248"],
    ),
}

# E_n from NUMERICS.md §2.2 (8 digits), for the cross-check only.
NUMERICS_E = {3: "7.9938064e-4", 5: "9.3457132e-6", 7: "1.0874975e-7"}


def polyval(c, x):
    acc = mp.mpf(0)
    for a in reversed(c):
        acc = acc * x + a
    return acc


def check_equioscillation(p, q, n, e_n):
    """Locate the interior extrema of e(x) and return max deviation of |e| from E_n."""
    err = lambda x: polyval(p, x) / polyval(q, x) - mp.exp(-x)
    # Substitution x = s/(1-s) maps [0,1) onto [0, inf); sample densely, refine sign changes of e'.
    grid = [mp.mpf(k) / 4000 for k in range(0, 4000)]
    xs = [s / (1 - s) for s in grid]
    de = lambda x: mp.diff(err, x)
    ds = [de(x) for x in xs[1:]]
    extrema = [mp.mpf(0)]
    for a, b, da, db in zip(xs[1:], xs[2:], ds, ds[1:]):
        if da * db < 0:
            extrema.append(mp.findroot(de, (a, b), solver="anderson"))
    values = [err(x) for x in extrema] + [polyval(p, 0) * 0 + p[-1] / q[-1]]
    assert len(values) == 2 * n + 2, f"n={n}: found {len(values)} extrema, expected {2 * n + 2}"
    for v, w in zip(values, values[1:]):
        assert v * w < 0, "extrema do not alternate"
    return max(abs(abs(v) - e_n) / e_n for v in values), extrema


def main():
    for n, (ps, qs) in TABLES.items():
        p = [mp.mpf(s) for s in ps]
        q = [mp.mpf(s) for s in qs]
        c0 = p[-1] / q[-1]
        e_n = abs(c0)
        dev, extrema = check_equioscillation(p, q, n, e_n)
        assert dev < mp.mpf("1e-30"), f"n={n}: equioscillation deviation {dev}"
        assert abs(e_n / mp.mpf(NUMERICS_E[n]) - 1) < 1e-7
        roots = mp.polyroots(list(reversed(q)), maxsteps=200, extraprec=200)
        dq = [k * q[k] for k in range(1, len(q))]
        print(f"// n = {n}: E_n = {mp.nstr(e_n, 20)}, equioscillation |e| = E_n to {mp.nstr(dev, 3)}"
              f" (relative) at {len(extrema) + 1} points incl. 0 and inf")
        print(f"c0 = {mp.nstr(c0, 20)}")
        for z in sorted(roots, key=lambda z: mp.re(z)):
            z = mp.mpc(z)
            res = polyval(p, z) / polyval(dq, z)
            if abs(mp.im(z)) < mp.mpf("1e-40"):
                print(f"real pole z = {mp.nstr(mp.re(z), 20)}, c = {mp.nstr(mp.re(res), 20)}")
            elif mp.im(z) > 0:
                print(f"z = {mp.nstr(mp.re(z), 20)} + {mp.nstr(mp.im(z), 20)}i, "
                      f"c = {mp.nstr(mp.re(res), 20)} + {mp.nstr(mp.im(res), 20)}i")
        print()


if __name__ == "__main__":
    main()
