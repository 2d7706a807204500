"""Segmentation ids: each rendered thing has an instance id (Blender's object pass index) and a class.

Shared by the Blender worker (which sets pass indices) and the host (which writes the class map)."""
from __future__ import annotations

# semantic classes: id -> name (0 is everything else: exterior, unlabelled)
CLASSES = {0: "background", 1: "cabin", 2: "seat", 3: "steering_wheel", 4: "driver", 5: "seat_belt",
           6: "phone", 7: "child_seat", 8: "child", 9: "luggage", 10: "colabottle", 11: "colacan",
           12: "interior_light", 13: "board"}

# instances: id -> (name, class name). `phone` is the phone in the driver's hand; the things on the
# co-driver seat are instances named like their scene features (phone_codriver_seat, ...)
INSTANCES = {
    1: ("cabin", "cabin"), 2: ("driver_seat", "seat"), 3: ("passenger_seat", "seat"), 4: ("rear_bench", "seat"),
    5: ("steering_wheel", "steering_wheel"), 6: ("driver", "driver"), 7: ("seat_belt", "seat_belt"),
    8: ("phone", "phone"), 9: ("child_seat", "child_seat"), 10: ("child", "child"), 11: ("luggage", "luggage"),
    12: ("colabottle_codriver_seat", "colabottle"), 13: ("colacan_codriver_seat", "colacan"),
    14: ("interior_light", "interior_light"), 15: ("board", "board"), 16: ("driver_face", "driver"),
    17: ("phone_codriver_seat", "phone"), 18: ("colacan_in_hand", "colacan"),
}
# driver_face: the driver's head (face, hair, ears); the rest of the body stays "driver". A body model
# that replaces the procedural driver keeps both pass indices (see README: per-feature visibility).
INSTANCE_ID = {name: i for i, (name, _) in INSTANCES.items()}
CLASS_ID = {name: i for i, name in CLASSES.items()}


def semantic_lut():
    """Array mapping instance id -> class id (for numpy indexing)."""
    import numpy as np
    lut = np.zeros(max(INSTANCES) + 1, dtype=np.uint8)
    for i, (_, cls) in INSTANCES.items():
        lut[i] = CLASS_ID[cls]
    return lut


def class_map() -> dict:
    return {"classes": {str(k): v for k, v in CLASSES.items()},
            "instances": {str(k): {"name": n, "class": c, "class_id": CLASS_ID[c]} for k, (n, c) in INSTANCES.items()}}
