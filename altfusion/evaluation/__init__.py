"""``altfusion evaluate``: every estimator in every paper scenario and fault scenario, as Monte
Carlo campaigns (:mod:`altfusion.montecarlo`), scored, tabulated and reported."""
