"""The field hash (the surrogate cache key) of every shape is pinned (issue #41): the
shape registry moved each shape into one module, and a cache written before that must
still be found. The literals were computed on main before the move; a change here means
every user's surrogate cache is recomputed, so it is never a silent one."""
import pytest

from tengfield.scene import Scene

SHELL = {"shape": "spherical-shell", "cavity_diameter_mm": 20.0, "shell_thickness_mm": 2.0,
         "electrode_band_mm": 2.0, "ball_diameter_mm": 8.0, "wall_permittivity": 3.0}
HEXAGONAL = {"shape": "hexagonal", "ball_diameter_mm": 5.0, "stroke_mm": 2.0,
             "tube_inner_radius_mm": 3.0, "tube_outer_radius_mm": 4.0,
             "plate_thickness_mm": 2.0, "wall_permittivity": 3.0}

#: name -> (scene sections, field hash on main before the shape registry)
PINNED = {
    "tube": ({}, "b60e9f08787bcb2dcfe3f4759b8cac5b3bf8488ea49dd5adb3b2c65053007eff"),
    "tube-3d": ({"field": {"method": "3d"}},
                "92859bd813d1f9671726991cf1c290199adce0e83ce36bddd0a07b5a1821541e"),
    "tube-offset": ({"field": {"method": "3d", "ball_offset_mm": 0.5}},
                    "8abcb86c116ca24994a6eb34f4fc14d18e2cf2f096350bbe2e01907800b77948"),
    "tube-ball": ({"device": {"ball_diameter_mm": 6.0, "stroke_mm": 3.0}},
                  "e2c07756c1a81d28fcc85ad5a695935f63abdb353d2757d5f9b303317b3777c2"),
    "tube-fine": ({"field": {"mesh_size_mm": 0.4, "degree": 1}},
                  "4e3441ced6824df1909bd4c98ab67969ec35ca84af71b18eae752ec5f0d20879"),
    "shell": ({"device": SHELL},
              "6fa970311dca2d3ac07865cf5082665d18c959042c47b7b3f5c43b51a5d50ef6"),
    "shell-3d": ({"device": SHELL, "field": {"method": "3d"}},
                 "f6ce919509b631c91ac91ae8ad57f77247391870e1f8fe577b07d08ad21fb502"),
    "shell-zr": ({"device": SHELL, "field": {"method": "3d", "ball_offset_mm": 1.0}},
                 "75647875a0cf748244a3542ffa361bc65f9668117db648d014fe92cd87775b68"),
    "shell-thin": ({"device": {**SHELL, "wall_permittivity": 1.0, "cavity_diameter_mm": 18.0}},
                   "f9d111b7bfbf8aee777b5710aa08f36dc0ad9c144d3cc939621841164f82a18e"),
    "hexagonal": ({"device": HEXAGONAL, "field": {"method": "3d"}},
                  "aa6ac6e39f8bf4db72aaa68981da8d6ee6d4be359ff1d9622e63868da3b93f2f"),
    "hexagonal-auto": ({"device": HEXAGONAL},
                       "6639f6895856960a1b8a19b165d99b9e57139249511c9b00570ecbdc005475fa"),
    "hexagonal-coarse": ({"device": HEXAGONAL,
                          "field": {"method": "3d", "degree": 1, "mesh_size_mm": 1.5,
                                    "domain_radius_mm": 20.0, "far_field": "robin"}},
                         "46715dfb4388a35bd45e1c49249ef7d413a27a76047840d7367e32802563b538"),
}


@pytest.mark.parametrize("name", PINNED)
def test_field_hash_is_byte_identical_to_main(name):
    sections, digest = PINNED[name]
    assert Scene.from_dict(sections).field_hash() == digest


def test_the_pins_tell_the_scenes_apart():
    # twelve scenes, twelve keys: a pin that every scene met would not hold anything
    assert len({digest for _, digest in PINNED.values()}) == len(PINNED)
