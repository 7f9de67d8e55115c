from __future__ import annotations

import dataclasses

import pytest

from pyrobots_aio import InvalidResourceError
from pyrobots_aio.resources import CompoundResource, Resource

L_ARM, R_ARM, HEAD = Resource("l_arm"), Resource("r_arm"), Resource("head")
ARMS = CompoundResource(L_ARM, R_ARM, name="arms")


def test_resources_compare_and_hash_by_value() -> None:
    assert Resource("l_arm") == L_ARM
    assert hash(Resource("l_arm")) == hash(L_ARM)
    assert Resource("l_arm") != R_ARM
    assert CompoundResource(L_ARM, R_ARM, name="arms") == ARMS
    assert CompoundResource(R_ARM, L_ARM, name="arms") != ARMS
    assert len({ARMS, CompoundResource(L_ARM, R_ARM, name="arms"), L_ARM}) == 2
    assert Resource("arms") != ARMS


def test_resources_are_immutable() -> None:
    with pytest.raises(dataclasses.FrozenInstanceError):
        L_ARM.name = "x"  # type: ignore[misc]
    with pytest.raises(dataclasses.FrozenInstanceError):
        ARMS.name = "x"  # type: ignore[misc]


def test_reprs() -> None:
    assert repr(L_ARM) == "Resource('l_arm')"
    assert repr(ARMS) == "CompoundResource(Resource('l_arm'), Resource('r_arm'), name='arms')"


def test_leaves_of_compounds_of_compounds_each_once_in_order() -> None:
    upper = CompoundResource(ARMS, HEAD, name="upper")
    body = CompoundResource(upper, Resource("wheels"), L_ARM, name="body")
    assert L_ARM.leaves == (L_ARM,)
    assert upper.leaves == (L_ARM, R_ARM, HEAD)
    assert body.leaves == (L_ARM, R_ARM, HEAD, Resource("wheels"))
    assert body.parts == (upper, Resource("wheels"), L_ARM)


def test_default_compound_name_joins_the_parts() -> None:
    assert CompoundResource(L_ARM, HEAD).name == "l_arm+head"


def test_compound_containing_itself_directly_is_rejected() -> None:
    with pytest.raises(InvalidResourceError) as info:
        CompoundResource(ARMS, HEAD, name="arms")
    assert str(info.value) == (
        "compound resource 'arms' contains itself: 'arms' > 'arms'; rename one of them"
    )


def test_compound_containing_itself_deeply_is_rejected() -> None:
    upper = CompoundResource(ARMS, HEAD, name="upper")
    with pytest.raises(InvalidResourceError) as info:
        CompoundResource(Resource("wheels"), upper, name="arms")
    assert str(info.value) == (
        "compound resource 'arms' contains itself: 'arms' > 'upper' > 'arms'; rename one of them"
    )


def test_compound_named_like_one_of_its_leaves_is_rejected() -> None:
    with pytest.raises(InvalidResourceError, match=r"'head' > 'head'"):
        CompoundResource(L_ARM, HEAD, name="head")


def test_compound_named_like_a_plain_part_reports_a_name_clash() -> None:
    with pytest.raises(InvalidResourceError) as info:
        CompoundResource(Resource("arms"), R_ARM, name="arms")
    assert str(info.value) == (
        "compound resource 'arms' has the name of its part Resource('arms') ('arms' > 'arms'); "
        "resources compare by name, so the two would clash: rename one of them"
    )
    upper = CompoundResource(ARMS, HEAD, name="upper")
    with pytest.raises(InvalidResourceError) as info:
        CompoundResource(upper, name="head")
    assert str(info.value) == (
        "compound resource 'head' has the name of its part Resource('head') "
        "('head' > 'upper' > 'head'); resources compare by name, so the two would clash: "
        "rename one of them"
    )


def test_compound_of_non_resources_is_rejected_naming_the_value() -> None:
    with pytest.raises(InvalidResourceError) as info:
        CompoundResource(L_ARM, "r_arm")  # type: ignore[arg-type]
    assert str(info.value) == (
        "'r_arm' is not a resource (needed as a part of a CompoundResource); "
        "declare it as Resource('r_arm') or CompoundResource(...)"
    )
    with pytest.raises(InvalidResourceError) as info:
        CompoundResource(L_ARM, 42, name="x")  # type: ignore[arg-type]
    assert str(info.value) == (
        "42 is not a resource (needed as a part of a CompoundResource); "
        "declare it as Resource('name') or CompoundResource(...)"
    )


def test_invalid_resource_errors_are_type_errors() -> None:
    with pytest.raises(TypeError):
        CompoundResource(None)  # type: ignore[arg-type]


def test_empty_compound_and_bad_names_are_rejected() -> None:
    with pytest.raises(InvalidResourceError) as info:
        CompoundResource(name="nothing")
    assert str(info.value) == (
        "CompoundResource needs at least one part, got none; e.g. CompoundResource(A, B)"
    )
    with pytest.raises(InvalidResourceError) as info:
        Resource("")
    assert str(info.value) == "a resource name must be a non-empty string, got ''"
    with pytest.raises(InvalidResourceError) as info:
        Resource(3)  # type: ignore[arg-type]
    assert str(info.value) == "a resource name must be a non-empty string, got 3"
    with pytest.raises(InvalidResourceError, match=r"got 7$"):
        CompoundResource(L_ARM, name=7)  # type: ignore[arg-type]


def test_a_resource_without_a_name_gets_a_generated_one_and_its_repr_says_so() -> None:
    first, second = Resource(), Resource()
    number = int(first.name.removeprefix("resource-"))
    assert (first.name, second.name) == (f"resource-{number}", f"resource-{number + 1}")
    assert (first.generated, second.generated, L_ARM.generated) == (True, True, False)
    assert first != second  # compared by name: two unnamed resources never clash
    assert first == first  # noqa: PLR0124 (by value, as any resource)
    assert repr(first) == f"<Resource 'resource-{number}' (name generated)>"
    both = CompoundResource(first, L_ARM)
    assert both.name == f"resource-{number}+l_arm"
    assert repr(both) == (
        f"CompoundResource(<Resource 'resource-{number}' (name generated)>, Resource('l_arm'), "
        f"name='resource-{number}+l_arm')"
    )


def test_an_explicit_name_of_the_generated_form_is_refused() -> None:
    with pytest.raises(InvalidResourceError) as info:
        Resource("resource-3")
    assert str(info.value) == (
        "resource names of the form resource-<number> are kept for generated names, got "
        "'resource-3'; give another name, e.g. Resource('arm'), or none to have one generated"
    )
    assert Resource("resource-x").name == "resource-x"  # only a number after the prefix is kept
    assert Resource("my-resource-3").name == "my-resource-3"
