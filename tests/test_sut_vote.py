"""Majority vote over repeats (tie rule, consistency) and key redaction."""
from __future__ import annotations

import pytest

from isu_validate.sut.redact import MASK, Redactor
from isu_validate.sut.vote import majority


def test_majority_and_consistency():
    runs = [({"a": "YES", "b": "NO"}, {}), ({"a": "YES", "b": "YES"}, {}), ({"a": "NO", "b": "YES"}, {})]
    vote = majority(["a", "b"], runs)
    assert vote.answers == {"a": "YES", "b": "YES"}
    assert vote.by_feature == {"a": pytest.approx(2 / 3), "b": pytest.approx(2 / 3)}
    assert vote.consistency == pytest.approx(2 / 3) and vote.unanimous == 0.0 and not vote.ties


def test_tie_keeps_the_answer_given_first_and_is_recorded():
    # "YES" is given first and is not the alphabetically first option: order, not the alphabet, decides
    runs = [({"a": "YES", "b": "NO"}, {}), ({"a": "NO", "b": "YES"}, {}), ({}, {}), ({"a": "NO", "b": "YES"}, {}),
            ({"a": "YES", "b": "NO"}, {})]
    vote = majority(["a", "b"], runs)
    assert vote.answers == {"a": "YES", "b": "NO"} and vote.ties == {"a": ["YES", "NO"], "b": ["NO", "YES"]}
    assert vote.by_feature["a"] == pytest.approx(2 / 5)  # the errored repeat counts as disagreeing
    three_way = majority(["c"], [({"c": "WHITE"}, {}), ({"c": "BLACK"}, {}), ({"c": "NONE"}, {})])
    assert three_way.answers == {"c": "WHITE"} and three_way.ties == {"c": ["WHITE", "BLACK", "NONE"]}


def test_unanswered_features_keep_their_status():
    runs = [({}, {"a": "invalid", "b": "missing"}), ({}, {"a": "missing", "b": "missing"})]
    vote = majority(["a", "b"], runs)
    assert vote.answers == {} and vote.status == {"a": "invalid", "b": "missing"} and vote.consistency == 0.0


def test_redaction():
    redact = Redactor(["my-secret-value-123", None, "abc"])  # short values are not masked (they are words)
    assert redact("key my-secret-value-123 here") == f"key {MASK} here"
    assert redact("Authorization: Bearer eyJhbGciOiJIUzI1NiJ9.payload") == f"Authorization: Bearer {MASK}"
    assert redact("use sk-proj-ABCDEFGHIJKLMNOP now") == f"use {MASK} now"
    assert redact("url?key=AIzaSyA1234567890abcdefghijklmnop") == f"url?key={MASK}"
    assert redact('{"api_key": "0123456789abcdef"}') == f'{{"api_key": "{MASK}"}}'
    assert redact("abc is fine, so is the seat_belt key") == "abc is fine, so is the seat_belt key"
