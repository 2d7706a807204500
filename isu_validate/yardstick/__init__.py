"""``recognise`` and ``bench recognise``: frames from runs, datasets, pairs and frame folders through the
photo-trained yardsticks of ``isu_validate/recognition``, and the report (summary.json, sheets, HTML)."""
