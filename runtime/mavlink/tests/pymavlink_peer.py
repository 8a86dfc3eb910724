#!/usr/bin/env python3
"""The cross-check's peer: pymavlink (an encoder and decoder written independently of the
Rust `mavlink` crate) on UDP loopback.

It listens on 127.0.0.1 (a free port, printed first as {"port": N}), prints every message it
decodes as {"received": TYPE, "src": [system, component], "fields": {...}}, and on a line
"vehicle" or "battery" on its standard input sends that group of vehicle messages to every
address that sent to it, printing each as {"sent": TYPE, "fields": {...}} and then {"done": GROUP}.
It ends when its standard input closes. Floats that are not numbers print as "NaN".
"""
import json
import math
import os
import select
import sys

os.environ["MAVLINK20"] = "1"
from pymavlink import mavutil  # noqa: E402

SYSTEM, COMPONENT = 1, 1


def clean(value):
    """A value JSON can carry: NaN as a string, bytes as text, lists element by element."""
    if isinstance(value, float) and math.isnan(value):
        return "NaN"
    if isinstance(value, bytes):
        return value.decode("utf-8", "replace").rstrip("\0")
    if isinstance(value, (list, tuple)):
        return [clean(v) for v in value]
    return value


def fields(msg):
    d = msg.to_dict()
    d.pop("mavpackettype", None)
    return {k: clean(v) for k, v in d.items()}


def quaternion(roll, pitch, yaw):
    """(w, x, y, z) of Euler angles applied yaw, then pitch, then roll."""
    cr, sr = math.cos(roll / 2), math.sin(roll / 2)
    cp, sp = math.cos(pitch / 2), math.sin(pitch / 2)
    cy, sy = math.cos(yaw / 2), math.sin(yaw / 2)
    return [
        cr * cp * cy + sr * sp * sy,
        sr * cp * cy - cr * sp * sy,
        cr * sp * cy + sr * cp * sy,
        cr * cp * sy - sr * sp * cy,
    ]


def vehicle_group(mav):
    """Every message the backend reads but the battery's, with known values."""
    m = mav
    return [
        m.heartbeat_encode(type=2, autopilot=3, base_mode=129, custom_mode=20, system_status=4,
                           mavlink_version=3),
        m.sys_status_encode(onboard_control_sensors_present=0, onboard_control_sensors_enabled=0,
                            onboard_control_sensors_health=0, load=250, voltage_battery=12400,
                            current_battery=1500, battery_remaining=77, drop_rate_comm=0,
                            errors_comm=0, errors_count1=0, errors_count2=0, errors_count3=0,
                            errors_count4=0),
        m.attitude_encode(time_boot_ms=1000, roll=0.1, pitch=-0.2, yaw=1.3, rollspeed=0.01,
                          pitchspeed=0.02, yawspeed=0.03),
        m.extended_sys_state_encode(vtol_state=0, landed_state=2),
        m.statustext_encode(severity=6, text=b"EKF3 IMU0 is using external nav data"),
        m.param_value_encode(param_id=b"WPNAV_SPEED_UP", param_value=250.0, param_type=9,
                             param_count=1, param_index=0),
        m.command_ack_encode(command=176, result=0),
        m.ekf_status_report_encode(flags=0x33F, velocity_variance=0.1, pos_horiz_variance=0.2,
                                   pos_vert_variance=0.3, compass_variance=0.4,
                                   terrain_alt_variance=0.5),
        m.local_position_ned_encode(time_boot_ms=1000, x=1.25, y=-0.5, z=-1.0, vx=0.1, vy=0.2,
                                    vz=-0.3),
        m.gimbal_device_attitude_status_encode(target_system=0, target_component=0,
                                               time_boot_ms=1000, flags=12,
                                               q=quaternion(0.0, -0.5, 0.2),
                                               angular_velocity_x=0.0, angular_velocity_y=0.0,
                                               angular_velocity_z=0.0, failure_flags=0),
        m.sim_state_encode(q1=quaternion(0.05, -0.1, 1.2)[0], q2=quaternion(0.05, -0.1, 1.2)[1],
                           q3=quaternion(0.05, -0.1, 1.2)[2], q4=quaternion(0.05, -0.1, 1.2)[3],
                           roll=0.05, pitch=-0.1, yaw=1.2, xacc=0.0, yacc=0.0, zacc=-9.8,
                           xgyro=0.0, ygyro=0.0, zgyro=0.0, lat=-35.363262, lon=149.165237,
                           alt=584.5, std_dev_horz=0.0, std_dev_vert=0.0, vn=0.4, ve=-0.2,
                           vd=0.1, lat_int=-353632620, lon_int=1491652370),
    ]


def battery_group(mav):
    return [
        mav.battery_status_encode(id=0, battery_function=0, type=1, temperature=2500,
                                  voltages=[4100] * 10, current_battery=1000,
                                  current_consumed=500, energy_consumed=100,
                                  battery_remaining=55),
    ]


def main():
    link = mavutil.mavlink_connection("udpin:127.0.0.1:0", source_system=SYSTEM,
                                      source_component=COMPONENT, dialect="ardupilotmega")
    print(json.dumps({"port": link.port.getsockname()[1]}), flush=True)
    groups = {"vehicle": vehicle_group, "battery": battery_group}
    while True:
        ready, _, _ = select.select([link.port, sys.stdin], [], [], 0.5)
        if link.port in ready:
            while True:
                msg = link.recv_match(blocking=False)
                if msg is None:
                    break
                out = {"received": msg.get_type(), "fields": fields(msg),
                       "src": [msg.get_srcSystem(), msg.get_srcComponent()]}
                print(json.dumps(out), flush=True)
        if sys.stdin in ready:
            line = sys.stdin.readline()
            if not line:
                return
            group = line.strip()
            if group not in groups:
                continue
            for msg in groups[group](link.mav):
                link.mav.send(msg)
                print(json.dumps({"sent": msg.get_type(), "fields": fields(msg)}), flush=True)
            print(json.dumps({"done": group}), flush=True)


if __name__ == "__main__":
    main()
