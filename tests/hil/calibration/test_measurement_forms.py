"""Each form of a measurements CSV against values computed here by hand, not by the reader's own
conversions: degrees against their radian twin, polar readings against the point they were computed
from, orientations against a known matrix, several markers against the columns written."""

from __future__ import annotations

import math

import numpy as np
import pytest

from hil.calibration.measurements import read_joints, read_measurements, write_measurements
from hil.errors import InputError

JOINTS = "q1,q2,q3,q4,q5,q6"
URDF = "shoulder_pan_joint,shoulder_lift_joint,elbow_joint,wrist_1_joint,wrist_2_joint,wrist_3_joint"
Q0 = "0.1,-1.2,1.3,-0.4,1.5,0.6"


def write(tmp_path, text, name="m.csv"):
    path = tmp_path / name
    path.write_text(text)
    return path


def rows(values: np.ndarray) -> str:
    return "\n".join(",".join(repr(float(v)) for v in row) for row in values) + "\n"


@pytest.fixture
def twins(tmp_path, rng):
    """Joint angles within every UR's limits and positions, written in hil's own form."""
    q = rng.uniform(-3.0, 3.0, size=(7, 6))
    p = rng.uniform(-2.0, 2.0, size=(7, 3))
    path = tmp_path / "rad.csv"
    write_measurements(path, q, p)
    return q, p, path


def test_a_degree_file_equals_its_radian_twin(tmp_path, twins):
    q, p, rad_path = twins
    header = ",".join(f"q{i}_deg" for i in range(1, 7)) + ",x,y,z"
    deg = read_measurements(write(tmp_path, header + "\n" + rows(np.hstack([q * 180 / math.pi, p])), "d.csv"))
    rad = read_measurements(rad_path)
    np.testing.assert_allclose(deg.q, rad.q, rtol=0, atol=1e-14)
    assert np.array_equal(deg.p, rad.p) and deg.rotation is None and deg.reflectors is None
    # a header without suffix, declared by the option; the URDF's joint names, in upper case too
    plain = write(tmp_path, JOINTS + ",x,y,z\n" + rows(np.hstack([q * 180 / math.pi, p])), "plain.csv")
    np.testing.assert_allclose(read_measurements(plain, "deg").q, q, rtol=0, atol=1e-14)
    urdf = write(tmp_path, URDF.upper() + ",X,Y,Z\n" + rows(np.hstack([q, p])), "urdf.csv")
    assert np.array_equal(read_measurements(urdf).q, q)
    joints_deg = write(tmp_path, ",".join(f"{n}_deg" for n in URDF.split(",")) + "\n"
                       + rows(q * 180 / math.pi), "j.csv")
    np.testing.assert_allclose(read_joints(joints_deg)[0], q, rtol=0, atol=1e-14)


def test_radians_that_look_like_degrees_are_refused_with_the_way_to_declare_them(tmp_path):
    path = write(tmp_path, f"{JOINTS},x,y,z\n90,-45,30,0,90,0,1,2,3\n")
    with pytest.raises(InputError, match=r"m.csv: line 2, column q1: 90 rad is beyond the joint limits.*"
                                         r"q1_deg\.\.q6_deg or pass --joint-units deg"):
        read_measurements(path)
    np.testing.assert_allclose(read_measurements(path, "deg").q[0],
                               [math.pi / 2, -math.pi / 4, math.pi / 6, 0, math.pi / 2, 0], atol=1e-15)


@pytest.mark.parametrize("hz,v,d,xyz", [
    # Hz clockwise from +y (north) seen from above, V from the zenith: x = d sinV sinHz, y = d sinV cosHz
    ("0", "90", "2", (0.0, 2.0, 0.0)),      # north, level
    ("90", "90", "2", (2.0, 0.0, 0.0)),     # a quarter turn clockwise: east
    ("270", "90", "2", (-2.0, 0.0, 0.0)),   # west
    ("123", "0", "1.5", (0.0, 0.0, 1.5)),   # straight up, whatever Hz
    ("180", "135", "2", (0.0, -math.sqrt(2), -math.sqrt(2))),  # south, 45° below the horizon
    ("0", "270", "2", (0.0, -2.0, 0.0)),    # face II: V past the zenith looks behind (south)
])
def test_polar_rows_computed_by_hand(tmp_path, hz, v, d, xyz):
    path = write(tmp_path, f"{JOINTS},hz_deg,v_deg,d\n{Q0},{hz},{v},{d}\n")
    np.testing.assert_allclose(read_measurements(path).p[0], xyz, rtol=0, atol=1e-12)


def test_a_polar_reading_lands_on_the_point_it_was_computed_from(tmp_path):
    x, y, z = 0.6, -0.8, 1.2
    d = math.sqrt(x * x + y * y + z * z)
    hz = math.atan2(x, y) % (2 * math.pi)  # clockwise from north
    v = math.acos(z / d)
    gon = 200 / math.pi
    text = (f"{JOINTS},hz,v,d\n{Q0},{hz!r},{v!r},{d!r}\n",
            f"{JOINTS},HZ_gon,V_gon,D_mm\n{Q0},{hz * gon!r},{v * gon!r},{d * 1000!r}\n",
            f"{JOINTS},hz_deg,v_deg,d_m\n{Q0},{math.degrees(hz + math.pi)!r},"
            f"{math.degrees(2 * math.pi - v)!r},{d!r}\n")  # the same point measured in face II
    for k, t in enumerate(text):
        np.testing.assert_allclose(read_measurements(write(tmp_path, t, f"p{k}.csv")).p[0], (x, y, z),
                                   rtol=0, atol=1e-12)


#: A known rotation: the frame's x axis along the instrument's y, y along z, z along x (a 120° turn
#: about (1,1,1)/√3). Its roll, pitch, yaw (R = Rz(yaw)·Ry(pitch)·Rx(roll)) are 90°, 0, 90°, its rotation
#: vector (2π/3)/√3·(1,1,1), its quaternion (w,x,y,z) = (½,½,½,½).
KNOWN = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])


@pytest.mark.parametrize("header,values", [
    ("roll_deg,pitch_deg,yaw_deg", "90,0,90"),
    ("phix1,phiy1,phiz1", f"{math.pi / 2!r},0,{math.pi / 2!r}"),
    ("rx,ry,rz", ",".join([repr(2 * math.pi / 3 / math.sqrt(3))] * 3)),
    ("qw,qx,qy,qz", "0.5,0.5,0.5,0.5"),
    ("qx,qy,qz,qw", "0.5,0.5,0.5,0.5"),
])
def test_orientations_give_the_known_matrix(tmp_path, header, values):
    path = write(tmp_path, f"{JOINTS},x,y,z,{header}\n{Q0},1,2,3,{values}\n{Q0},1,2,3,{values}\n")
    meas = read_measurements(path)
    assert meas.rotation is not None and meas.rotation.shape == (2, 3, 3)
    np.testing.assert_allclose(meas.rotation[1], KNOWN, rtol=0, atol=1e-12)


def test_roll_pitch_yaw_compose_as_rz_ry_rx(tmp_path):
    roll, pitch, yaw = 0.3, -0.7, 2.1
    c, s = math.cos, math.sin
    rx = np.array([[1, 0, 0], [0, c(roll), -s(roll)], [0, s(roll), c(roll)]])
    ry = np.array([[c(pitch), 0, s(pitch)], [0, 1, 0], [-s(pitch), 0, c(pitch)]])
    rz = np.array([[c(yaw), -s(yaw), 0], [s(yaw), c(yaw), 0], [0, 0, 1]])
    path = write(tmp_path, f"{JOINTS},x,y,z,roll,pitch,yaw\n{Q0},1,2,3,{roll},{pitch},{yaw}\n")
    np.testing.assert_allclose(read_measurements(path).rotation[0], rz @ ry @ rx, rtol=0, atol=1e-12)


def test_several_markers_and_figaroh_header(tmp_path):
    # FIGAROH's header: marker 1's position and roll, pitch, yaw, then the URDF joint names
    header = f"x1,y1,z1,phix1,phiy1,phiz1,x2,y2,z2,{URDF}"
    text = (f"{header}\n0.9,0.3,1.2,0,0,0,0.8,0.2,1.1,{Q0}\n"
            f"1.0,-0.4,1.4,{math.pi / 2!r},0,{math.pi / 2!r},0.5,0.6,0.7,{Q0}\n")
    meas = read_measurements(write(tmp_path, text))
    assert meas.reflectors is not None and meas.reflectors.shape == (2, 2, 3)
    np.testing.assert_array_equal(meas.p, [[0.9, 0.3, 1.2], [1.0, -0.4, 1.4]])
    np.testing.assert_array_equal(meas.reflectors[:, 1], [[0.8, 0.2, 1.1], [0.5, 0.6, 0.7]])
    np.testing.assert_allclose(meas.rotation[0], np.eye(3), atol=1e-15)
    np.testing.assert_allclose(meas.rotation[1], KNOWN, atol=1e-12)
    np.testing.assert_allclose(meas.q, [[0.1, -1.2, 1.3, -0.4, 1.5, 0.6]] * 2)
    sub = meas.subset(np.array([False, True]))
    assert sub.rotation.shape == (1, 3, 3) and sub.reflectors.shape == (1, 2, 3) and sub.lines.tolist() == [3]


@pytest.mark.parametrize("text,message", [
    (f"{JOINTS},x,y,z,hz,v,d\n{Q0},1,2,3,0,1,2\n", r"line 1: both Cartesian \(x,y,z\) and polar \(hz,v,d\)"),
    (f"{JOINTS},x1,y1,z1,x,y,z\n{Q0},1,2,3,1,2,3\n", r"both Cartesian .* and markers"),
    (f"{JOINTS},{URDF},x,y,z\n", r"both q1\.\.q6 .* and URDF joint names"),
    (f"q1_deg,q2_deg,q3,q4,q5,q6,x,y,z\n{Q0},1,2,3\n", r"line 1: the joint columns mix units"),
    ("q1,Q1_deg,q2,q3,q4,q5,q6,x,y,z\n", r"column\(s\) q1 appear twice"),
    (f"{JOINTS},x,y,z,roll,pitch,yaw,rx,ry,rz\n{Q0},1,2,3,0,0,0,0,0,0\n", r"keep one orientation form"),
    (f"{JOINTS},hz,v,d\n{Q0},0,1.5,-2\n", r"line 2, column d: -2 m is not a distance"),
    (f"{JOINTS},hz,v,d_mm\n{Q0},0,1.5,90000\n", r"line 2, column d_mm: 90000 mm is not a distance"),
    (f"{JOINTS},hz_deg,v,d\n{Q0},400,1.5,2\n", r"column hz_deg: 400 deg is more than a turn \(360°\)$"),
    (f"{JOINTS},x,y,z,qw,qx,qy,qz\n{Q0},1,2,3,0,0,0,0\n", r"line 2, columns qw,qx,qy,qz: norm 0 "),
    (f"{JOINTS},x1,y1,z1,x2,z2\n{Q0},1,2,3,4,5\n", r"line 1: marker 2 is missing column\(s\) y2"),
    (f"{JOINTS},a,b,c\n{Q0},1,2,3\n", r"line 1: no position columns: expected x,y,z"),
    (f"{JOINTS},x,y,z,pitch\n{Q0},1,2,3,0\n", r"missing column\(s\) roll, yaw"),
])
def test_forms_that_cannot_be_read_are_one_line_naming_line_and_column(tmp_path, text, message):
    with pytest.raises(InputError, match=message) as err:
        read_measurements(write(tmp_path, text))
    assert "\n" not in str(err.value) and str(err.value).startswith(str(tmp_path / "m.csv"))


def test_the_declaration_must_agree_with_the_header(tmp_path):
    header = ",".join(f"q{i}_deg" for i in range(1, 7))
    path = write(tmp_path, f"{header}\n10,20,30,40,50,60\n")
    assert read_joints(path, "deg")[0].shape == (1, 6)
    with pytest.raises(InputError, match=r"line 1: the header declares the joints in deg \(q1_deg\) but "
                                         r"--joint-units says rad"):
        read_joints(path, "rad")


def test_unknown_unit_suffixes_are_other_columns(tmp_path):
    # x_deg is no position column, so the Cartesian form is incomplete and says what it misses
    with pytest.raises(InputError, match=r"missing column\(s\) x "):
        read_measurements(write(tmp_path, f"{JOINTS},x_deg,y,z\n{Q0},1,2,3\n"))
    text = f"{JOINTS},x_mm,y_mm,z_mm,note\n{Q0},1000,-2000,30,hi\n"
    meas = read_measurements(write(tmp_path, text, "mm.csv"))
    np.testing.assert_allclose(meas.p[0], [1.0, -2.0, 0.03], rtol=0, atol=1e-15)


def test_figaroh_angles_read_as_pinocchio_composes_them(tmp_path, rng):
    """FIGAROH turns phix,phiy,phiz into a matrix with pinocchio's rpyToMatrix: the reader agrees."""
    import pinocchio as pin

    rpy = rng.uniform(-math.pi, math.pi, size=(5, 3))
    path = write(tmp_path, "x1,y1,z1,phix1,phiy1,phiz1," + URDF + "\n"
                 + rows(np.hstack([np.ones((5, 3)), rpy, np.zeros((5, 6))])))
    meas = read_measurements(path)
    for k in range(5):
        np.testing.assert_allclose(meas.rotation[k], pin.rpy.rpyToMatrix(rpy[k]), rtol=0, atol=1e-12)
