"""URDF texts of the fuzz registry: the six-legged robot whose joints interleave in ``q``
(:data:`HEXAPOD_URDF`), Go2's description, one-leg pieces, and malformed, hostile and oddly encoded
descriptions."""

from __future__ import annotations

import functools
import re

import numpy as np
from urdf_helpers import joint as _urdf_joint
from urdf_helpers import links as _urdf_links

import spotkin as sk

from .slots import REJECT


def _hexapod_urdf() -> str:
    """Six roll-pitch-pitch legs in three pairs at different x (and heights), with mixed axis signs
    (a knee about -y takes positive limits to bend back) and offsets; the joints are written hips
    first, then thighs, then knees, so the whole-body q interleaves the legs (as tests/test_robot.py's
    hexapod)."""
    legs = [  # name, hip origin, axes, knee limits, a, b, c
        (
            "L1",
            "0.3 0.12 0",
            ("1 0 0", "0 1 0", "0 1 0"),
            (-2.6, -0.2),
            "0 0.08 0",
            "0.02 0 -0.2",
            "0 0 -0.21",
        ),
        (
            "R1",
            "0.31 -0.1 0.01",
            ("-1 0 0", "0 -1 0", "0 -1 0"),
            (0.2, 2.6),
            "0 -0.07 0.01",
            "0.02 0 -0.2",
            "0 0 -0.21",
        ),
        (
            "L2",
            "0.02 0.15 -0.01",
            ("1 0 0", "0 -1 0", "0 1 0"),
            (-2.6, -0.2),
            "0 0.08 0",
            "-0.015 0.005 -0.22",
            "0 0 -0.21",
        ),
        (
            "R2",
            "-0.01 -0.16 0",
            ("1 0 0", "0 1 0", "0 -1 0"),
            (0.2, 2.6),
            "0.01 -0.09 0",
            "0.02 0 -0.2",
            "0 0 -0.21",
        ),
        (
            "L3",
            "-0.33 0.11 0.005",
            ("-1 0 0", "0 1 0", "0 1 0"),
            (-2.6, -0.2),
            "0 0.08 0",
            "0.02 0 -0.2",
            "0.01 0.01 -0.2",
        ),
        (
            "R3",
            "-0.3 -0.12 -0.02",
            ("-1 0 0", "0 -1 0", "0 1 0"),
            (-2.6, -0.2),
            "0 -0.085 -0.01",
            "0.02 0 -0.2",
            "0 0 -0.21",
        ),
    ]
    link_names = ["base"]
    joints = [[], [], [], []]
    for name, hip, axes, knee, a, b, c in legs:
        parts = [f"{name}_{part}" for part in ("hip", "thigh", "calf", "foot")]
        link_names += parts
        joints[0].append(
            _urdf_joint(
                f"{name}_hip_joint", "revolute", "base", parts[0], hip, axis=axes[0], limits=(-0.7, 0.7)
            )
        )
        joints[1].append(
            _urdf_joint(
                f"{name}_thigh_joint", "revolute", parts[0], parts[1], a, axis=axes[1], limits=(-2.2, 2.2)
            )
        )
        joints[2].append(
            _urdf_joint(f"{name}_calf_joint", "revolute", parts[1], parts[2], b, axis=axes[2], limits=knee)
        )
        joints[3].append(_urdf_joint(f"{name}_foot_joint", "fixed", parts[2], parts[3], c))
    body = _urdf_links(*link_names) + "".join(j for group in joints for j in group)
    return f'<?xml version="1.0"?><robot name="hexapod">{body}</robot>'


HEXAPOD_URDF = _hexapod_urdf()
HEXAPOD_LEGS = ("L1", "R1", "L2", "R2", "L3", "R3")


@functools.cache
def go2_text() -> str:
    return sk.robots.text("go2")


@functools.cache
def go2_kinematics() -> str:
    return re.sub(r"<inertial>.*?</inertial>", "", go2_text(), flags=re.S)


def vec_text(v) -> str:
    """A vector as spotkin.urdf.describe prints it."""
    return "(" + ", ".join(f"{round(float(x), 12) + 0.0:.6g}" for x in np.ravel(v)) + ")"


def _urdf(body: str, name: str = "r") -> str:
    return f'<?xml version="1.0"?><robot name="{name}">{body}</robot>'


def _one_leg(prefix="L", parent="base", hip="0.2 0.1 0") -> str:
    """Links and joints of one roll-pitch-pitch leg hanging from ``parent``."""
    names = [f"{prefix}_{part}" for part in ("hip", "thigh", "calf", "foot")]
    return _urdf_links(*names) + "".join(
        [
            _urdf_joint(
                f"{prefix}_hip_joint", "revolute", parent, names[0], hip, axis="1 0 0", limits=(-0.7, 0.7)
            ),
            _urdf_joint(
                f"{prefix}_thigh_joint",
                "revolute",
                names[0],
                names[1],
                "0 0.08 0",
                axis="0 1 0",
                limits=(-2, 2),
            ),
            _urdf_joint(
                f"{prefix}_calf_joint",
                "revolute",
                names[1],
                names[2],
                "0 0 -0.2",
                axis="0 1 0",
                limits=(-2.6, -0.2),
            ),
            _urdf_joint(f"{prefix}_foot_joint", "fixed", names[2], names[3], "0 0 -0.2"),
        ]
    )


@functools.cache
def bad_urdfs() -> dict:
    """Malformed or unusable descriptions: name -> (text, expect, why)."""
    leg = '<link name="base"/>' + _one_leg()
    go2 = go2_text()
    laughs = "".join(f'<!ENTITY l{i + 1} "{f"&l{i};" * 10}">' for i in range(9))
    return {
        "empty": ("", REJECT, "value"),
        "whitespace": (" \n\t", REJECT, "value"),
        "not_xml": ("hello", REJECT, "value"),
        "truncated": (go2[: len(go2) // 2], REJECT, "value"),
        "not_robot": ('<sdf version="1.6"/>', REJECT, "value"),
        "no_links": ('<robot name="r"/>', REJECT, "value"),
        "loop": (
            _urdf(
                '<link name="base"/><link name="a"/><link name="b"/>'
                + _urdf_joint("j0", "fixed", "base", "a", "0 0 0")
                + _urdf_joint("j1", "revolute", "a", "b", "0 0 0", axis="1 0 0", limits=(-1, 1))
                + _urdf_joint("j2", "revolute", "b", "a", "0 0 0", axis="1 0 0", limits=(-1, 1))
            ),
            REJECT,
            "value",
        ),
        "self_parent": (
            _urdf(leg.replace('parent link="L_thigh"', 'parent link="L_calf"')),
            REJECT,
            "value",
        ),
        "two_roots": (_urdf(leg + '<link name="orphan"/>'), REJECT, "value"),
        "undeclared_link": (_urdf(leg.replace('<link name="L_calf"/>', "")), REJECT, "value"),
        "duplicate_link": (_urdf(leg + '<link name="L_calf"/>'), REJECT, "value"),
        "duplicate_joint": (_urdf(leg.replace("L_calf_joint", "L_thigh_joint")), REJECT, "value"),
        "no_limit": (
            _urdf(leg.replace('<limit lower="-2.6" upper="-0.2" effort="10" velocity="5"/>', "")),
            REJECT,
            "value",
        ),
        "inverted_limit": (
            _urdf(leg.replace('lower="-2.6" upper="-0.2"', 'lower="-0.2" upper="-2.6"')),
            REJECT,
            "value",
        ),
        "nan_origin": (_urdf(leg.replace('xyz="0 0 -0.2"', 'xyz="nan 0 -0.2"', 1)), REJECT, "value"),
        "inf_origin": (_urdf(leg.replace('xyz="0 0 -0.2"', 'xyz="1e999 0 -0.2"', 1)), REJECT, "value"),
        "short_origin": (_urdf(leg.replace('xyz="0 0 -0.2"', 'xyz="0 -0.2"', 1)), REJECT, "value"),
        "word_origin": (_urdf(leg.replace('xyz="0 0 -0.2"', 'xyz="0 zero -0.2"', 1)), REJECT, "value"),
        "zero_axis": (_urdf(leg.replace('xyz="0 1 0"', 'xyz="0 0 0"', 1)), REJECT, "value"),
        "floating": (_urdf(leg.replace('type="fixed"', 'type="floating"')), REJECT, "value"),
        "unknown_type": (_urdf(leg.replace('type="fixed"', 'type="ball"')), REJECT, "value"),
        "no_parent": (_urdf(leg.replace('<parent link="L_calf"/>', "")), REJECT, "value"),
        "negative_mass": (
            _urdf(
                leg.replace(
                    '<link name="L_hip"/>',
                    '<link name="L_hip"><inertial><mass value="-1"/>'
                    '<inertia ixx="1" iyy="1" izz="1"/></inertial></link>',
                )
            ),
            REJECT,
            "value",
        ),
        "asymmetric_inertia": (
            _urdf(
                leg.replace(
                    '<link name="L_hip"/>',
                    '<link name="L_hip"><inertial><mass value="1"/>'
                    '<inertia ixx="1" iyy="1" izz="-5"/></inertial></link>',
                )
            ),
            REJECT,
            "value",
        ),
        "no_legs": (  # a 2-joint arm only: nothing recognised
            _urdf(
                '<link name="base"/><link name="a"/><link name="b"/>'
                + _urdf_joint("j1", "revolute", "base", "a", "0 0 0.1", axis="0 0 1", limits=(-1, 1))
                + _urdf_joint("j2", "revolute", "a", "b", "0 0 0.3", axis="0 1 0", limits=(-1, 1))
            ),
            REJECT,
            "value",
        ),
        "yaw_leg": (_urdf(leg.replace('xyz="1 0 0"', 'xyz="0 0 1"', 1)), REJECT, "value"),  # z-y-y
        "laughs": (  # entity expansion (a billion laughs): refused by the parser, quickly
            f'<?xml version="1.0"?><!DOCTYPE r [<!ENTITY l0 "lol">{laughs}]><robot name="&l9;">'
            '<link name="a"/></robot>',
            REJECT,
            "value",
        ),
        "external_entity": (
            '<?xml version="1.0"?><!DOCTYPE r [<!ENTITY x SYSTEM "file:///etc/passwd">]>'
            '<robot name="&x;"><link name="a"/></robot>',
            REJECT,
            "value",
        ),
        "nul": (go2.replace("<robot", "<robot\0", 1), REJECT, "value"),
        "surrogate": (go2.replace('name="base"', 'name="\ud800"', 1), REJECT, ""),
    }


@functools.cache
def odd_urdfs() -> dict:
    """Unusual but valid descriptions: name -> text."""
    go2 = go2_text()
    body = go2.split("?>", 1)[1] if go2.startswith("<?xml") else go2
    return {
        "comments": go2.replace("<link", "<!-- a comment --><link", 3),
        "no_declaration": body,
        "extra_tags": go2.replace(
            "</robot>",
            '<gazebo reference="base"><material>x</material></gazebo><transmission name="t"/>'
            '<material name="m"/></robot>',
        ),
        "mimic": _urdf(
            '<link name="base"/>'
            + _one_leg()
            + _one_leg("R", hip="0.2 -0.1 0").replace(
                '<limit lower="-2.6"', '<mimic joint="L_calf_joint"/><limit lower="-2.6"', 1
            )
        ),
        "one_leg": _urdf('<link name="base"/>' + _one_leg()),
        "deep_fixed": _urdf(  # the leg hangs below 300 fixed links
            '<link name="base"/>'
            + _urdf_links(*(f"f{i}" for i in range(300)))
            + "".join(
                _urdf_joint(f"fj{i}", "fixed", "base" if i == 0 else f"f{i - 1}", f"f{i}", "0 0 0.001")
                for i in range(300)
            )
            + _one_leg(parent="f299")
        ),
    }


def latin1_urdf() -> bytes:
    """Go2 declared and encoded as ISO-8859-1, with a non-ASCII link name (not a leg's)."""
    go2 = go2_text()
    body = go2.split("?>", 1)[1] if go2.startswith("<?xml") else go2
    return ('<?xml version="1.0" encoding="ISO-8859-1"?>' + body.replace('"radar"', '"r\xe4dar"')).encode(
        "latin-1"
    )
