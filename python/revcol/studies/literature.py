"""Published reference values for hard disks and spheres, with where each one was read.

Units throughout: m = sigma = kT = 1 (sigma the diameter); phi the packing (area or volume)
fraction; n the number density n sigma^d (3D n = 6 phi / pi, 2D n = 4 phi / pi).

Every value below was read through the revcol session's stored-source search tools (web-page
beginnings and abstracts, GitHub files). Most full texts were NOT reachable: only abstracts or
first pages. Where a number could not be read it is left out and the gap is said so here.

Sources
-------
[YH04] I.-C. Yeh, G. Hummer, "System-size dependence of diffusion coefficients and viscosities
    from molecular dynamics simulations with periodic boundary conditions", J. Phys. Chem. B 108,
    15873-15879 (2004). Read on its first page (datapdf.com) and an abstract (scientific.net):
    D0 = D_PBC + 2.837297 kT / (6 pi eta L) for a cubic box of side L; it "quantitatively
    accounts" for the size dependence of D for water, LJ and hard-sphere fluids; shear
    viscosities of water and LJ show no significant size dependence. (DOI not seen.)
[P19] "Thermodynamic and dynamical properties of the hard sphere system revisited by molecular
    dynamics simulation", Phys. Chem. Chem. Phys. 21(13), 6886-6901 (2019), DOI
    10.1039/C9CP00903E. Authors per the brief: Pieprzyk, Bannerman, Branka, Chudak, Heyes. The
    only record read (a bibliography file on GitHub) names other authors (Santos, Yuste, Lopez de
    Haro), so one of the two is wrong; check before citing. NO table of D or eta from it was
    reachable: HS3D_TRANSPORT below is empty on purpose.
[SH] "Transport coefficients of hard sphere fluids" (abstract, discovery.researcher.life; authors
    and journal not shown there; the brief ties it to Sigurgeirsson & Heyes, Mol. Phys. 2003,
    unverified). MD up to N = 32000 to packing 0.57. Only D shows a substantial N dependence for
    N < 500 at equilibrium fluid packings (< 0.494); D increases with N, most at packing 0.3-0.35.
    The two viscosities and the conductivity fit X/X0 = 1/[1 - (phi/phi1)]^m (X0 the dilute value);
    the fitted phi1, m are not in the abstract.
[EW85] "Molecular-dynamics calculations of the velocity autocorrelation function: Hard-sphere
    results" (scilit abstract; Erpenbeck & Wood by the brief, unverified): 108 to 4000 spheres at
    V/V0 = 25 to 1.6; the VACF follows finite-size mode-coupling theory with Enskog transport
    coefficients beyond roughly 15 to 30 mean free times (by density), for volumes down to 2 V0.
    No D or eta values in the abstract.
[G23] arXiv:2305.06287, "Poles of hydrodynamic spectral functions and Einstein-Helfand formulas
    for transport coefficients" (ar5iv opening): computes the hard-sphere fluid's transport
    coefficients by Einstein-Helfand formulas; its values were beyond the readable opening.
Searched for and NOT found in any readable text (the search tools' pages, code and docs corpora):
    tables of D/D_E or eta/eta_E against density from Pieprzyk et al. (PCCP 2019), Sigurgeirsson &
    Heyes (2003), Erpenbeck & Wood (1991, PRA 43, 4254: only cited by title in an abstract of
    Ruckenstein & Liu, Ind. Eng. Chem. Res. 36, 3927 (1997)), Alder, Gass & Wainwright (1970).
[S87] R. J. Speedy, "Diffusion in the hard sphere fluid", Mol. Phys. 62(2), 509-515 (1987),
    doi 10.1080/00268978700102371 (scilit abstract). A fit of simulated D to the whole fluid
    range, exact at the ideal gas, valid up to n = 1.08, with a singularity at n = 1.09 where D
    vanishes; D0 = (3/8) sigma (kT/(pi m))^(1/2) as printed (per unit n). The fit's own formula
    is lost in the stored text.
[G24] arXiv:2402.09348, "On the system size dependence of the diffusion coefficients in MD
    simulations: A simple correction formula for pure dense fluids" (abstract): D_N = D_inf
    (1 - gamma N^(-1/3)) with gamma ~ 1.0 for a cubic box. (Authors not shown.)
[JK01] J. Jaeckle, H. Kawai, Physica A 291, 184-196 (2001) (abstract): binary hard spheres,
    radius ratio 0.85; D(N=5832) vs D(N=216) differ by 11% to 18% for phi 0.533 to 0.563.
[W06] "Velocity autocorrelation functions of hard-sphere fluids..." (Semantic Scholar page, 2006;
    names Williams, Bryant only from the page URL): positive t^(-3/2) tail for every phi below freezing; for phi
    0.45-0.48 the VACF goes negative before the positive tail; at 0.494 no Alder tail is seen.
[I08] M. Isobe, arXiv:0801.4094, "Long time tail of the velocity autocorrelation function in a
    two-dimensional moderately dense hard disk fluid" (abstract): in 2D the Green-Kubo D
    diverges logarithmically (the "2D long-time-tail problem"); with 10^6 disks the tail decays
    slightly faster than 1/t, compared with self-consistent mode coupling ~ 1/(t sqrt(ln t)).
[C17] B. Choi, K. H. Han, C. Kim, P. Talkner, A. Kidera, E. K. Lee, arXiv:1709.06435, "Nature of
    self-diffusion in two-dimensional fluids" (abstract): kinematic viscosity finite in the
    thermodynamic limit; VACF ~ 1/(t sqrt(ln t)) with a rescaled time; finite-size D studied.
    No 2D value of D at finite N could be read from any source.
Lyapunov exponents (no numerical value of lambda_max could be read from any source):
[DPH96] Ch. Dellago, H. A. Posch, W. G. Hoover, "Lyapunov instability in a system of hard disks in
    equilibrium and nonequilibrium steady states", Phys. Rev. E 53(2), 1485-1501 (1996),
    doi 10.1103/PhysRevE.53.1485. Read only in a secondary annotated bibliography (GitHub):
    64 and 144 hard disks; lambda_max and the KS entropy closely follow the collision frequency;
    at low density lambda_1 ~ -rho ln rho (Krylov). Tables/figures not reachable.
[vZ98] R. van Zon, H. van Beijeren, Ch. Dellago, "Largest Lyapunov exponent for many particle
    systems at low densities", Phys. Rev. Lett. 80, 2035-2038 (1998), doi
    10.1103/PhysRevLett.80.2035, arXiv:chao-dyn/9710020 (abstract): Krylov's density dependence
    but a larger prefactor; disk and sphere simulations agree with a clock model; slow
    convergence with N (Brunet-Derrida). The prefactor and constant term were NOT reachable.
[KS97] arXiv:chao-dyn/9706019, "The Kolmogorov-Sinai entropy for dilute gases in equilibrium"
    (abstract): h_KS / N = a nu [-ln n + b + O(n)], nu the single-particle collision frequency,
    n the reduced density; a agrees with simulation "excellently", b less well. a, b not read.
[dW05] A. S. de Wijn, arXiv:nlin/0501001 (abstract): h_KS = N nu A [ln n + B + O(n)]; improved B.
[DHP02] Ch. Dellago, W. G. Hoover, H. A. Posch, Phys. Rev. E 65, 056216 (2002),
    doi 10.1103/PhysRevE.65.056216: N dependences of Lyapunov spectra follow power laws.
[F04] C. Forster, R. Hirschl, H. A. Posch, W. G. Hoover, arXiv:nlin/0211047, "Perturbed
    phase-space dynamics of hard-disk fluids": the lambda_max perturbation is localized, the
    active fraction of particles -> 0 as N -> infinity.
The 3D hard-sphere Lyapunov paper (Dellago & Posch, Physica A 1997) was not found at all.

Units caveat for Lyapunov exponents: the low-density results above are all of the form
lambda = nu x f(n), i.e. naturally per mean free time; with m = sigma = kT = 1, nu is the
per-particle collision rate (collision_rate below) and lambda in inverse time units is nu x f.
"""
from __future__ import annotations

import math

# ----------------------------------------------------------------------------- data
YEH_HUMMER_XI = 2.837297  # [YH04], cubic periodic box, dimensionless

SIZE_GAMMA_CUBIC = 1.0  # [G24] "gamma ~ 1.0" for a cubic box: D_N = D_inf (1 - gamma N^-1/3)

SPEEDY_1987 = {  # [S87], abstract text
    "n_max_fitted": 1.08,      # highest n sigma^3 of the (metastable) fluid in the fit
    "n_singular": 1.09,        # n sigma^3 where the fitted D vanishes
}

SIZE_EFFECTS_3D = {  # [SH] abstract: qualitative, no numbers for D(N)
    "N_max": 32000,
    "phi_fluid_max": 0.494,
    "phi_strongest_N_dependence": (0.30, 0.35),
    "N_below_which_D_depends_on_N": 500,
    "viscosity_N_dependence": "not substantial for N >= 500 (abstract)",
}

BINARY_HS_SIZE_EFFECT = {  # [JK01] binary, radius ratio 0.85: D(5832)/D(216) - 1
    "phi": (0.533, 0.563), "relative_difference": (0.11, 0.18), "N": (216, 5832),
}

HS3D_TRANSPORT = {}  # [P19] tables NOT reachable: no D*, eta* values recorded (do not fill from memory)

HD2D_DIFFUSION = {  # [I08], [C17]: no finite-N value of D was readable
    "green_kubo_D": "diverges logarithmically with time / system size in 2D [I08]",
    "tail_Isobe_N": 1_000_000,
    "tail_scmct": "1/(t sqrt(ln t)) [I08, C17]",
}

LYAPUNOV = {  # no numerical lambda_max readable; what was read:
    "DPH96_N_disks": (64, 144),  # secondary summary only
    "low_density_form_KS_per_particle": "nu * a * (-ln n + b) [KS97]; nu * A * (ln n + B) [dW05]",
    "largest_exponent_form": "Krylov density dependence, larger prefactor [vZ98]; constants not read",
}


# ------------------------------------------------------------------------ functions
def number_density(phi: float, dim: int) -> float:
    """n sigma^d from the packing fraction."""
    if dim == 3:
        return 6.0 * phi / math.pi
    if dim == 2:
        return 4.0 * phi / math.pi
    raise ValueError("dim must be 2 or 3")


def contact_value(phi: float, dim: int) -> float:
    """g(sigma+): Carnahan-Starling (3D), Henderson (2D), as in revcol.studies.transport."""
    if dim == 3:
        return (1.0 - phi / 2.0) / (1.0 - phi) ** 3
    if dim == 2:
        return (1.0 - 7.0 * phi / 16.0) / (1.0 - phi) ** 2
    raise ValueError("dim must be 2 or 3")


def collision_rate(phi: float, dim: int, kT: float = 1.0, g: float | None = None) -> float:
    """Enskog collisions per particle per unit time (docs/physics.md): 4 n g sqrt(pi kT) in 3D,
    2 n g sqrt(pi kT) in 2D. g = 1 gives the dilute (Boltzmann) rate nu of [KS97, dW05]."""
    n = number_density(phi, dim)
    g = contact_value(phi, dim) if g is None else g
    return (4.0 if dim == 3 else 2.0) * n * g * math.sqrt(math.pi * kT)


def enskog_D(phi: float, dim: int, kT: float = 1.0, g: float | None = None) -> float:
    """Enskog self-diffusion, first Chapman-Enskog approximation (revcol.studies.transport):
    3D 3 / (8 n g) sqrt(kT / pi); 2D 1 / (2 n g) sqrt(kT / pi)."""
    n = number_density(phi, dim)
    g = contact_value(phi, dim) if g is None else g
    pref = 3.0 / 8.0 if dim == 3 else 0.5
    return pref / (n * g) * math.sqrt(kT / math.pi)


def enskog_eta(phi: float, dim: int, kT: float = 1.0, g: float | None = None) -> float:
    """Enskog shear viscosity, first Sonine approximation, 3D only.

    eta0 = 5 / (16 sqrt(pi)) sqrt(kT); bulk kappa_E = eta0 (64 pi / 45) n^2 g;
    eta_E = eta0 (1 + 4 pi n g / 15)^2 / g + (3/5) kappa_E.
    Read in an Enskog.h file on GitHub (search-tool id 33961188241, "Enskog expression for shear
    viscosity"); the dilute eta0 = (5/16) sqrt(m kT / pi) / sigma^2 agrees with the
    Chapman-Enskog docs of EntropyScaling.jl (Omega = 1 for hard spheres). In the usual form
    eta_E / eta0 = b n [1/y + 4/5 + c y], y = b n g, b = 2 pi / 3, this gives
    c = 4/25 + 48/(25 pi) = 0.7712; literature quoting c = 0.7614 uses a Sonine-corrected eta0
    (not verified here), so compare ratios to eta_E from one convention only.
    2D: no source for the hard-disk Enskog viscosity was reachable -> NotImplementedError."""
    if dim != 3:
        raise NotImplementedError("2D Enskog viscosity: no source read (see module docstring)")
    n = number_density(phi, dim)
    g = contact_value(phi, dim) if g is None else g
    eta0 = 5.0 / (16.0 * math.sqrt(math.pi)) * math.sqrt(kT)
    kappa = eta0 * (64.0 * math.pi / 45.0) * n * n * g
    return eta0 * (1.0 + 4.0 * math.pi * n * g / 15.0) ** 2 / g + 0.6 * kappa


def yeh_hummer(D_N: float, eta: float, L: float, kT: float = 1.0) -> float:
    """[YH04] D_inf = D_N + 2.837297 kT / (6 pi eta L), cubic periodic box of side L (3D only)."""
    return D_N + YEH_HUMMER_XI * kT / (6.0 * math.pi * eta * L)


def size_gamma(D_N: float, N: int, gamma: float = SIZE_GAMMA_CUBIC) -> float:
    """[G24] D_inf = D_N / (1 - gamma N^(-1/3)), gamma ~ 1.0 for a cubic box (3D)."""
    return D_N / (1.0 - gamma * N ** (-1.0 / 3.0))


def lyapunov_low_density(n: float, dim: int, A: float, B: float, kT: float = 1.0) -> float:
    """The low-density form nu * A * (ln n + B) of [dW05] (KS entropy per particle; [vZ98] say
    lambda_max has the same Krylov n-dependence), nu the dilute collision rate per particle.

    n is n sigma^d. A and B must be supplied: their published values (for lambda_max or for
    h_KS / N, disks or spheres) could not be read, so there are deliberately no defaults.
    Returns a rate in units of sqrt(kT / m) / sigma; divide by nu for per-mean-free-time units."""
    if dim not in (2, 3):
        raise ValueError("dim must be 2 or 3")
    phi = n * (math.pi / 6.0 if dim == 3 else math.pi / 4.0)
    nu = collision_rate(phi, dim, kT, g=1.0)
    return nu * A * (math.log(n) + B)


if __name__ == "__main__":
    for d, p in [(2, 0.3), (2, 0.5), (3, 0.1), (3, 0.3), (3, 0.45)]:
        eta = enskog_eta(p, d) if d == 3 else float("nan")
        print(f"d={d} phi={p}: g={contact_value(p, d):.4f} D_E={enskog_D(p, d):.4f} "
              f"eta_E={eta:.4f} nu_E={collision_rate(p, d):.4f}")
