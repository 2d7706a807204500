"""Sentences from the reference ISU's predictions, with varied phrasing.

The phrasing varies with the image (a hash picks among equivalent wordings), so that
caption metrics see natural variation rather than one fixed template, while the same
image always gets the same caption.
"""
from __future__ import annotations

OPENERS = ["The image shows", "In the car there is", "The cabin camera sees", "Visible in the scene is"]
DRIVER = {"MALE": ["a man", "a male driver"], "FEMALE": ["a woman", "a female driver"]}
EMOTION = {"HAPPY": ["who is smiling", "who looks happy"], "SERIOUS": ["who looks serious", "with a serious face"]}
SHIRT = {"BLACK": "a black T-shirt", "WHITE": "a white T-shirt"}
BELT = {"YES": ["wearing a seat belt", "with the seat belt fastened"],
        "NO": ["not wearing a seat belt", "without a seat belt"]}
PHONE_IN_HAND = {"YES": ["holding a phone", "using a mobile phone"], "NO": []}
ORIENTATION = {"FRONT_FACING": "front-facing", "REAR_FACING": "rear-facing"}
ON_CODRIVER_SEAT = {"phone_codriver_seat": "a mobile phone", "colabottle_codriver_seat": "a cola bottle",
                    "colacan_codriver_seat": "a cola can"}
PLACES = {"PASSENGER": "on the passenger seat", "BACK": "on the back seat"}


def _pick(options, variant: int, salt: int):
    if isinstance(options, str):
        return options
    return options[(variant // (salt + 1)) % len(options)] if options else ""


def describe(p: dict[str, str], variant: int = 0) -> str:
    sentences = [_driver_sentence(p, variant)]
    if p.get("child_seat") == "YES":
        orientation = ORIENTATION.get(p.get("child_seat_orientation", ""), "")
        child = "with a child in it" if p.get("child") == "YES" else "which is empty"
        sentences.append(f"There is a {orientation} child seat {child}".replace("  ", " "))
    if p.get("luggage") == "YES":
        colour = {"YELLOW": "yellow ", "ANTHRACITE": "anthracite "}.get(p.get("luggage_colour", ""), "")
        place = PLACES.get(p.get("luggage_position", ""), "in the car")
        sentences.append(f"A {colour}suitcase lies {place}")
    things = [name for key, name in ON_CODRIVER_SEAT.items() if p.get(key) == "YES"]
    if things:
        listed = things[0] if len(things) == 1 else ", ".join(things[:-1]) + " and " + things[-1]
        opener = _pick(["There is also ", "The car also contains ", "I can also see "], variant, 7)
        sentences.append(opener + listed
                         + _pick([" on the passenger seat", " on the front passenger seat"], variant, 8))
    return ". ".join(s[0].upper() + s[1:] for s in sentences if s) + "."


def _driver_sentence(p: dict[str, str], variant: int) -> str:
    parts = [_pick(OPENERS, variant, 0), _pick(DRIVER.get(p.get("driver_gender"), ["a driver"]), variant, 1)]
    parts.append(_pick(EMOTION.get(p.get("driver_emotion"), []), variant, 2))
    if p.get("tshirt_colour") in SHIRT:
        parts.append("in " + SHIRT[p["tshirt_colour"]])
    parts.append(_pick(BELT.get(p.get("seat_belt"), []), variant, 3))
    phone = _pick(PHONE_IN_HAND.get(p.get("phone_position"), []), variant, 4)
    if phone:
        parts.append("and " + phone)
    return " ".join(x for x in parts if x)
