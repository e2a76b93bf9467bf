"""Job of ``workflow/rules/variance.smk``: the variance fields of one scene at one SPP (Eq. 1)."""

from __future__ import annotations

from .common import log


def variance_job(left, right, out, *, estimator="seeds", allow_mixed_backends=False) -> None:
    """Run the estimator on one scene's render stores at one SPP and store its fields.

    Writes ``results/{renderer}/{estimator}/variance/{scene}/spp{spp}.zarr``
    (:func:`stereovar.io.contracts.variance_store`), with the renders' provenance. Renders
    made with different back ends (renderer version or variant, e.g. by cluster nodes that
    resolved ``auto`` differently) stop the job unless ``allow_mixed_backends``
    (:func:`stereovar.preflight.check_backends`).
    """
    from ..estimators import get_estimator
    from ..io.contracts import render_provenance, variance_store
    from ..io.store import open_dataset, read_errors, store_error, write_dataset
    from ..preflight import check_backends, stored_backends
    from ..rig import VIEWS

    left, right = list(left), list(right)
    check_backends(stored_backends([*left, *right]), allow_mixed=allow_mixed_backends)
    ds = get_estimator(estimator).estimate(left, right)
    try:
        first = open_dataset(left[0])
        # a store written from a bare DataArray carries its provenance on the variable
        own = next(iter(first.data_vars.values())).attrs if first.data_vars else {}
        provenance = render_provenance({**own, **first.attrs})
    except read_errors() as err:
        raise store_error(left[0], f"{type(err).__name__}: {err}") from None
    ds = variance_store(ds, estimator=estimator, provenance=provenance)
    n_bad = {v: int((~ds["finite"].sel(view=v).values).sum()) for v in VIEWS}
    write_dataset(ds, out)
    log.info(
        "%s variance over %d renders per view; pixels excluded for non-finite values: "
        "left %d, right %d",
        estimator,
        ds.attrs["n_seeds"],
        n_bad["left"],
        n_bad["right"],
    )
