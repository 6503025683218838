"""An integer no float can hold is refused with the parameter named, not an OverflowError."""

import pytest

from scatterbench import models
from scatterbench.models.params import check_real


@pytest.mark.parametrize("big", [10**400, -(10**400)])
def test_check_real_refuses_an_integer_no_float_holds(big):
    with pytest.raises(ValueError, match=r"^x must be a finite real number in \[0, 1\]; got -?1000"):
        check_real("x", big, 0.0, 1.0)


def test_a_model_parameter_of_10_to_the_400_names_the_parameter():
    with pytest.raises(ValueError, match="^sigma must be"):
        models.ExponentialSlopes(sigma=10**400)
