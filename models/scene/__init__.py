"""Scenes: a sample and a measurement described once, in TOML, built into the
cheapest model that represents them.

``load(path)`` reads and validates a scene file (standard-library ``tomllib``);
every error names the file, the key and the allowed values.  ``Scene.build()``
returns the composite model holding only the mechanisms the scene declares,
and ``Scene.mechanisms()`` says which ones and why; ``Scene.assemble()`` returns the
model with the decisions it measured (point source, detector aperture) and why.

One module per concern: :mod:`~scatterbench.models.scene.schema` (the tables and keys, validated),
:mod:`~scatterbench.models.scene.table` (the one table from the names a file uses to model classes:
its keys are the classes' declared parameters, ``*_deg`` in degrees, and the classes
validate the values), :mod:`~scatterbench.models.scene.editing` (dotted keys for fits and sweeps),
:mod:`~scatterbench.models.scene.assembly` (the mechanisms) and :mod:`~scatterbench.models.scene.decisions`
(what is measured), with :class:`Scene` in :mod:`~scatterbench.models.scene.core`.

Schema (angles in degrees in files, as everywhere outside the Python API)::

    name = "Aluminium flakes under a clear coat"

    [illumination]
    theta_i_deg = 60.0
    polarization = "linear:45"     # unpolarized | s | p | +45 | -45 | left | right | linear:<deg> | [I, Q, U, V]
    wavelength_nm = 632.8
    source = "collimated"          # collimated | point
    distance_mm = 500.0            # point source: its height above the sample plane (seed 001's d)
    sample_radius_mm = 10.0        # point source: illuminated radius

    [coating]                      # optional clear layer over the substrate/flakes
    index = 1.5
    [coating.roughness]            # optional: rough top surface (its own facet reflection)
    distribution = "gaussian"
    sigma = 0.02
    shadowing = "smith"            # none (default) | smith | smith-correlated (not with a
                                   # Monte Carlo [volume] under it: interface = "rough")
    [coating.film]                 # optional: thin films on the coating's top surface
                                   # (models.Films, coating_films of the models), from the
                                   # ambient down, at [illumination] wavelength_nm (then
                                   # required); with facets (model = "facet") or a [volume]
                                   # under a smooth interface, not with cook-torrance or the
                                   # Monte Carlo volume
    layers = [{index = 1.2247, thickness_nm = 129.2}]

    [substrate]                    # the flakes or the substrate under the coating
    index = [1.37, 7.62]           # [n, k], a number, or "inf" (perfect conductor)
    distribution = "exponential"   # omit for a flat (specular) substrate; any of
                                   # exponential | gaussian (sigma: rms slope),
                                   # anisotropic-exponential | anisotropic-gaussian
                                   # (sigma_x, sigma_y, rotation_deg), gaussian-angle |
                                   # exponential-angle (sigma_deg), ggx (alpha: a width;
                                   # GGX's rms slope is infinite), anisotropic-ggx
                                   # (alpha_x, alpha_y, rotation_deg); each with coverage
    sigma = 0.1
    coverage = 1.0
    shadowing = "none"             # none (default, seed 000) | smith | smith-correlated

    [substrate.film]               # optional: thin films on the facets/flakes (models.FilmStack),
                                   # from the incident side down, over the substrate index,
                                   # at [illumination] wavelength_nm (then required)
    layers = [{index = [2.6, 0.0], thickness_nm = 130.0}]

    [volume]                       # optional volume scatterer (pigment) in the coating
    ...

    # or, instead of the facet substrate: seed 001's Cook-Torrance metal (under the
    # coating's varnish when there is a [coating])
    [substrate]
    model = "cook-torrance"
    index = [2.29, 3.37]
    m = 0.03                       # or m_parallel, m_perpendicular and stroke_angle_deg (Eq. 19)
    convention = "corrected"       # corrected (default) | paper; old keys: normalization, solid_angle
    shadowing = "blinn"            # blinn | none | smith

    # or an empirical model with no interface
    [substrate]
    model = "maxwell-beard"        # facet (default) | cook-torrance | maxwell-beard
    index = 1.5                    # Fresnel reflectance of the specular facets
    distribution = "gaussian"      # facet slopes of the specular term
    sigma = 0.05
    rho_d = 0.02                   # Lambertian BRDF, 1/sr
    rho_v = 0.01                   # volumetric coefficient, 1/sr: 2 rho_v / (cos ti + cos tr)
    tau_deg = 15.0                 # shadowing/obscuration parameters (defaults: the model's)
    omega_deg = 40.0
    polarized = true               # facet Mueller matrix on the specular term (false: published scalar form)

    [detector]
    aperture_deg = 0.7
"""

from .assembly import Mechanism
from .core import Scene, from_dict, load, loads
from .decisions import Assembly
from .schema import SceneError
from .table import DISTRIBUTIONS, TABLE

__all__ = [
    "Scene",
    "SceneError",
    "Mechanism",
    "Assembly",
    "load",
    "loads",
    "from_dict",
    "DISTRIBUTIONS",
    "TABLE",
]
