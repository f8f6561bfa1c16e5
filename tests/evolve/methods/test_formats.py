"""Controller formats are owned by their methods: each method module registers the formats it
writes (evolve/methods/formats.py), and a champion's controller is read by its tag alone."""

import pytest

from evolve.methods import formats
from evolve.methods.formats import controller_of
from evolve.methods.sgr import record as sgr_record
from evolve.nn.dense import FORMAT as DENSE_FORMAT
from evolve.nn.graph import DERIVED_FORMAT, FORMAT


def test_every_format_the_methods_write_is_registered_by_them():
    assert {DENSE_FORMAT, sgr_record.FORMAT, FORMAT, DERIVED_FORMAT, None} <= set(formats.READERS)


def test_a_format_registered_by_a_new_module_is_read_by_its_tag(monkeypatch):
    """Adding a method's format is one registration; nothing else names it."""
    monkeypatch.setattr(formats, "READERS", dict(formats.READERS))
    formats.register("toy-controller-1", lambda record: ("toy", record["controller"]["gain"]))
    assert controller_of({"controller": {"format": "toy-controller-1", "gain": 3}}) == ("toy", 3)


def test_an_unknown_tag_is_refused_naming_it_and_a_tag_is_not_taken_twice(monkeypatch):
    with pytest.raises(ValueError, match="unknown controller format 'nope-1'; known formats: .*sgr-"):
        controller_of({"controller": {"format": "nope-1"}})
    monkeypatch.setattr(formats, "READERS", dict(formats.READERS))
    with pytest.raises(ValueError, match="registered already"):
        formats.register(FORMAT, lambda record: None)
