"""The Blender worker process: ``python -m isu_validate.render.blender.main``.

The only entry point that imports bpy. Requests arrive as JSON lines on stdin; one JSON line per
request goes back on the file descriptor named by ISU_RESPONSE_FD. Blender's own console output goes
to this process's stdout/stderr, which the host sends to a log file."""
from __future__ import annotations

import json
import os
import sys
import time
import traceback


def main() -> int:
    t0 = time.perf_counter()
    import bpy  # noqa: F401  (imported here so its start-up cost is reported)
    from .studio import Studio
    respond = os.fdopen(int(os.environ["ISU_RESPONSE_FD"]), "w", buffering=1)
    respond.write(json.dumps({"ok": True, "op": "hello", "import_s": time.perf_counter() - t0,
                              "pid": os.getpid()}) + "\n")
    studio = None
    for line in sys.stdin:
        if not line.strip():
            continue
        request = json.loads(line)
        op = request.get("op")
        try:
            if op == "quit":
                respond.write(json.dumps({"ok": True, "op": "quit"}) + "\n")
                return 0
            if op == "init":
                t = time.perf_counter()
                studio = Studio(request["cabin"])
                reply = {"build_s": time.perf_counter() - t}
            elif op == "render":
                reply = _render(studio, request)
            elif op == "bounds":
                studio.apply(request["features"], request.get("extras", {}), request.get("people", {}))
                reply = {"bounds": studio.bounds()}
            elif op == "device":   # which device Blender renders on, asked before the first GPU frame
                from .device import select_device
                used, note = select_device(studio.scene, request["device"])
                reply = {"device": used, "device_note": note}
            elif op == "ping":
                reply = {}
            else:
                raise ValueError(f"unknown op {op!r}")
            respond.write(json.dumps({"ok": True, "op": op, **reply}) + "\n")
        except Exception as exc:  # report, keep serving: the host decides whether to retry
            print(traceback.format_exc(), file=sys.stderr, flush=True)
            respond.write(json.dumps({"ok": False, "op": op, "error": f"{type(exc).__name__}: {exc}"}) + "\n")
    return 0


def _render(studio, request: dict) -> dict:
    if studio is None:
        raise RuntimeError("render before init")
    t, cpu = time.perf_counter(), time.process_time()
    studio.set_preset(request["preset"])
    studio.set_camera(request["camera"])
    studio.apply(request["features"], request.get("extras", {}), request.get("people", {}))
    update_s = time.perf_counter() - t
    print(f"[isu] render {request.get('tag', '')}", flush=True)
    times = studio.render(request["exr"])
    if request.get("footprints"):   # the parts' unoccluded footprints, for per-feature visibility
        from .parts import write_footprints
        times.update(write_footprints(studio.scene, request["footprints"], request["camera"],
                                      request["footprint_file"]))
    # CPU seconds of all render threads: a contention-free measure of the work a frame takes
    return {"update_s": update_s, **times, "cpu_s": time.process_time() - cpu, "device": studio.device,
            "device_note": studio.device_note}


if __name__ == "__main__":
    sys.exit(main())
