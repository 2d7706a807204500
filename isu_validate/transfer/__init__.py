"""``transfer``: a SUT on labelled real photographs beside renders, and how far the photos are from the
renders: what the renders taught that holds on real photos.

    summary = measure_transfer(TransferSettings(real=("real/statefarm",), labels=("statefarm.toml",),
                               sut_options={"model_dir": "runs/mine/model"}), "transfer/mine")
    summary["sets"]["statefarm"]["scores"]["phone_position"]["balanced_accuracy"]

Rooms: ``ask`` (the questions a photo's labels answer, through the SUT and its reply cache), ``scores``
(accuracy, balanced accuracy, intervals, baseline, confusion, AUC), ``renders`` (the same SUT on renders:
a dataset's, or a reference model's stored held-out features), ``measure`` (the folder: summary.json,
answers.jsonl), ``report`` (HTML), ``arguments`` (the real-set options of both commands). The photos are
read by ``isu_validate.realphotos``; KID/FID by ``isu_validate.realism``.
"""
from ..lazy import lazy_names

__all__ = ["TransferSettings", "measure_transfer"]
__getattr__, __dir__ = lazy_names(__name__, {"TransferSettings": ".measure", "measure_transfer": ".measure"})
