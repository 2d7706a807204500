"""One module per kind of SUT; ``isu_validate.sut.registry`` maps spec schemes to them."""
