"""The example model passes scatterbench's conformance kit, one test per check."""

from lambert_specular import LambertSpecular

from scatterbench.validation.testing import parametrize_with_checks


@parametrize_with_checks([LambertSpecular(), LambertSpecular(albedo=1.0, weight=0.5, roughness=0.05, n=2.5)])
def test_conformance(model, check):
    check(model)
