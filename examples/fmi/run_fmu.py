#!/usr/bin/env python3
"""Run an FMU exported by `pneumo export-fmu` through the FMI 2.0 C functions
with Python's ctypes - an importer in a page.

    python3 examples/fmi/run_fmu.py meter_out.fmu

Unpacks the FMU, instantiates it, sets the input `command` to 1 from 0.1 s
to 2 s (the meter-out cylinder's extend and retract), steps it every 10 ms
and prints the position x every 0.5 s. Names come from modelDescription.xml.
"""
import ctypes
import os
import sys
import tempfile
import xml.etree.ElementTree as ET
import zipfile

LOGGER = ctypes.CFUNCTYPE(None, ctypes.c_void_p, ctypes.c_char_p, ctypes.c_int, ctypes.c_char_p, ctypes.c_char_p)


class Callbacks(ctypes.Structure):
    _fields_ = [("logger", LOGGER), ("allocateMemory", ctypes.c_void_p), ("freeMemory", ctypes.c_void_p),
                ("stepFinished", ctypes.c_void_p), ("componentEnvironment", ctypes.c_void_p)]


def log(env, instance, status, category, message):
    print(f"[{instance.decode()}] {category.decode()}: {message.decode()}", file=sys.stderr)


def main(fmu_path, t_end=4.0, h=0.01):
    folder = tempfile.mkdtemp(prefix="fmu_")
    zipfile.ZipFile(fmu_path).extractall(folder)
    md = ET.parse(os.path.join(folder, "modelDescription.xml")).getroot()
    identifier = md.find("CoSimulation").get("modelIdentifier")
    vr = {v.get("name"): int(v.get("valueReference")) for v in md.iter("ScalarVariable")}
    lib = ctypes.CDLL(os.path.join(folder, "binaries", "linux64", identifier + ".so"))
    lib.fmi2Instantiate.restype = ctypes.c_void_p
    lib.fmi2Instantiate.argtypes = [ctypes.c_char_p, ctypes.c_int, ctypes.c_char_p, ctypes.c_char_p,
                                    ctypes.POINTER(Callbacks), ctypes.c_int, ctypes.c_int]
    for f in ("fmi2SetupExperiment", "fmi2EnterInitializationMode", "fmi2ExitInitializationMode", "fmi2DoStep",
              "fmi2GetReal", "fmi2SetReal", "fmi2Terminate", "fmi2FreeInstance"):
        getattr(lib, f).argtypes = None
    callbacks = Callbacks(LOGGER(log), None, None, None, None)
    uri = "file://" + os.path.join(folder, "resources")
    c = ctypes.c_void_p(lib.fmi2Instantiate(b"demo", 1, md.get("guid").encode(), uri.encode(),
                                            ctypes.byref(callbacks), 0, 0))
    assert c.value, "fmi2Instantiate failed"
    lib.fmi2SetupExperiment(c, 0, ctypes.c_double(0), ctypes.c_double(0), 1, ctypes.c_double(t_end))
    lib.fmi2EnterInitializationMode(c)
    lib.fmi2ExitInitializationMode(c)

    def set_real(name, value):
        ref, val = (ctypes.c_uint * 1)(vr[name]), (ctypes.c_double * 1)(value)
        assert lib.fmi2SetReal(c, ref, ctypes.c_size_t(1), val) == 0

    def get_real(name):
        ref, val = (ctypes.c_uint * 1)(vr[name]), (ctypes.c_double * 1)()
        assert lib.fmi2GetReal(c, ref, ctypes.c_size_t(1), val) == 0
        return val[0]

    steps = round(t_end / h)
    for k in range(steps):
        t = k * h
        set_real("command", 1.0 if 0.1 - 1e-9 <= t < 2.0 - 1e-9 else 0.0)
        assert lib.fmi2DoStep(c, ctypes.c_double(t), ctypes.c_double(h), 1) == 0, f"fmi2DoStep failed at {t} s"
        if (k + 1) % round(0.5 / h) == 0:
            print(f"t = {(k + 1) * h:4.2f} s   x = {get_real('x') * 1e3:7.2f} mm")
    lib.fmi2Terminate(c)
    lib.fmi2FreeInstance(c)


if __name__ == "__main__":
    main(sys.argv[1])
