"""``isu-validate bench evaluate``: what judging one scene costs, per metric and per torch thread count.

Speed against error: the metric values at every thread count are compared with the
1-thread values (they must agree to float rounding; only the speed may differ).
"""
from __future__ import annotations

import time


def register_bench(sub) -> None:
    p = sub.add_parser("evaluate", help="judge cost per scene: parsing, VQA, caption metrics by torch threads")
    p.add_argument("--scenes", type=int, default=20, help="scenes to judge per setting (default: %(default)s)")
    p.add_argument("--threads", default="1,2", help="torch thread counts to compare (default: %(default)s)")
    p.add_argument("--space", default="isu-paper")
    p.add_argument("--seed", type=int, default=1)
    p.set_defaults(func=cmd_bench_evaluate)


def _captions(space, scenes) -> list[str]:
    """Plausible SUT captions: the reference, reworded and partly wrong, so metrics do real work."""
    from isu_validate.evaluate.reference_caption import reference_caption

    swaps = {"female": "male", "white": "black", "happy": "serious", "The image shows": "I can see"}
    out = []
    for i, scene in enumerate(scenes):
        text = reference_caption(space, scene)
        for a, b in list(swaps.items())[: i % 4 + 1]:
            text = text.replace(a, b)
        out.append(text)
    return out


def cmd_bench_evaluate(args) -> int:
    import numpy as np

    from isu_validate.space import load_space
    from isu_validate.sut import build_request
    from isu_validate.sut.parse import parse_vqa
    from isu_validate.evaluate import models, similarity, text_metrics
    from isu_validate.evaluate.reference_caption import reference_caption
    from isu_validate.evaluate.vqa import VQAJudge
    from isu_validate.protocols import SUTResponse

    space = load_space(args.space)
    scenes = space.sample(np.random.default_rng(args.seed), args.scenes)
    captions = _captions(space, scenes)
    references = [reference_caption(space, s) for s in scenes]

    start = time.perf_counter()
    models.minilm()
    for c, r in zip(captions, references):  # WordNet reads and caches each word's synsets on first lookup
        text_metrics.meteor(c, r)
    print(f"load: MiniLM + WordNet {time.perf_counter() - start:.2f} s (once per process)")

    judge, start = VQAJudge(space), time.perf_counter()
    for scene in scenes:
        request = build_request(space, scene, "x.png", "vqa")
        reply = "```json\n" + str({q.key: q.truth.lower() for q in request.questions}) + "\n```"
        parsed = parse_vqa(reply, request.questions)
        judge.judge(scene, request, SUTResponse(answers=parsed.answers, extra={"status": parsed.status}))
    print(f"vqa: parse + judge {1000 * (time.perf_counter() - start) / len(scenes):.2f} ms per scene")

    metrics = {"f_emb": similarity.f_emb, "f_bleu": text_metrics.bleu, "f_meteor": text_metrics.meteor,
               "f_bert": lambda c, r: similarity.bertscore(c, r)["f1"]}
    baseline = None
    print(f"{'threads':>7} " + " ".join(f"{m + ' ms':>12}" for m in metrics) + f" {'scene ms':>10} {'max |diff|':>11}")
    for threads in [int(t) for t in args.threads.split(",")]:
        models.METRIC_THREADS = threads
        times, values = {}, {}
        for name, fn in metrics.items():
            start = time.perf_counter()
            values[name] = np.array([fn(c, r) for c, r in zip(captions, references)])
            times[name] = 1000 * (time.perf_counter() - start) / len(scenes)
        baseline = baseline or values
        diff = max(float(np.abs(values[m] - baseline[m]).max()) for m in metrics)
        print(f"{threads:>7} " + " ".join(f"{times[m]:>12.1f}" for m in metrics)
              + f" {sum(times.values()):>10.1f} {diff:>11.2e}")
    return 0
