"""One set of world keywords, taken the same way by every environment and by
``demonstrations`` (``blockstack.world``)."""

import pytest

import blockstack
from blockstack.vector import StackVectorEnv
from blockstack.world import KEYWORDS, World


def demonstrations(**world):
    """``demonstrations`` as a maker of something with a world: its arrays' shapes and, for
    the rest, the ``World`` it read (the same reader's)."""
    data = blockstack.demonstrations(1, backend=world.pop("backend", "grid"), obs="planes", **world)
    return data


MAKERS = {
    "StackEnv": lambda **w: blockstack.StackEnv(**w),
    "BlocksWorldEnv": lambda **w: blockstack.BlocksWorldEnv(**w),
    "StackVectorEnv": lambda **w: StackVectorEnv(2, **w),
    "StackGoalEnv": lambda **w: blockstack.StackGoalEnv(**w),
    "demonstrations": demonstrations,
}

#: A value other than the default for every world keyword, each making a world alone.
VALUES = {
    "blocks": 2,
    "goal": "2,0,1",
    "grid": (6, 5),
    "reward": "step-cost",
    "backend": "grid",
    "horizon": 50,
    "profile": "original",
    "protocol": "paper",
    "start": "paper",
    "view": "side",
    "max_episode_steps": 40,
}


def test_every_world_keyword_is_listed_once():
    assert sorted(VALUES) == sorted(KEYWORDS)
    assert KEYWORDS[-1] == "max_episode_steps" and "horizon" in KEYWORDS


@pytest.mark.parametrize("keyword", sorted(VALUES))
@pytest.mark.parametrize("maker", sorted(MAKERS))
def test_every_maker_takes_every_world_keyword(maker, keyword):
    value = VALUES[keyword]
    if maker == "BlocksWorldEnv" and keyword in ("view", "profile", "start"):
        # The side view is BlocksWorld-v0's by name, and it starts from random towers.
        with pytest.raises(ValueError):
            MAKERS[maker](**{keyword: value})
        return
    if maker == "BlocksWorldEnv" and keyword == "goal":
        value = "0,1/2"
    made = MAKERS[maker](**{keyword: value})
    if maker == "demonstrations":
        blocks = value if keyword == "blocks" else 3
        width, height = value if keyword == "grid" else (7, 7)
        assert made["observations"].shape[1:] == (width, height, blocks + 1)
        return
    world = made.world
    assert isinstance(world, World)
    expected = {"max_episode_steps": ("horizon", value), "goal": ("goal", value)}.get(keyword, (keyword, value))
    assert getattr(world, expected[0]) == expected[1], (maker, keyword)


@pytest.mark.parametrize("maker", sorted(MAKERS))
def test_a_keyword_that_is_not_a_world_keyword_is_refused_alike(maker):
    with pytest.raises(ValueError, match="unknown keyword\\(s\\) blokcs: the world keywords are blocks, goal"):
        MAKERS[maker](blokcs=3)


@pytest.mark.parametrize("maker", sorted(MAKERS))
@pytest.mark.parametrize(
    "keyword, value, says",
    [
        ("blocks", -1, "blocks"),
        ("blocks", 2.5, "blocks"),
        ("horizon", 2**40, "horizon"),
        ("max_episode_steps", "long", "max_episode_steps"),
        ("backend", 3, "backend"),
        ("profile", None, "profile"),
        ("grid", "seven", "grid"),
        ("goal", "0,1//2", "empty"),
    ],
)
def test_a_bad_world_keyword_is_one_value_error_naming_it_everywhere(maker, keyword, value, says):
    with pytest.raises(ValueError, match=says):
        MAKERS[maker](**{keyword: value})
