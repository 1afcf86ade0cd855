"""The estimators by FMU model name: each paper's estimator, the baseline and AltitudeEKF.

The systems of the catalog (fault suite, replay systems), the evaluation, the reproductions
and the command line take the estimators they fly from here.
"""

from altfusion.estimators.altitude_ekf import AltitudeEKF
from altfusion.estimators.bao import BaoDriftEstimator
from altfusion.estimators.base import Estimator
from altfusion.estimators.baseline import BaselineKF
from altfusion.estimators.hajiyev import HajiyevAdaptiveEstimator
from altfusion.estimators.whang import WhangGAEstimator
from altfusion.estimators.xu import XuSHAEKF
from altfusion.estimators.yang import YangFusionKF

ESTIMATOR_CLASSES: dict[str, type[Estimator]] = {
    "BaselineKF": BaselineKF,
    "HajiyevAdaptiveEstimator": HajiyevAdaptiveEstimator,
    "WhangGAEstimator": WhangGAEstimator,
    "BaoDriftEstimator": BaoDriftEstimator,
    "YangFusionKF": YangFusionKF,
    "XuSHAEKF": XuSHAEKF,
    "AltitudeEKF": AltitudeEKF,
}
"""The estimator core classes, by FMU model name (the FMU of each wraps its class)."""
