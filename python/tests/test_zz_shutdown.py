"""Last (pytest runs files in name order): destroying the device kept by every test before reports no message,
leaked objects included, and the next call makes a device again."""

import volcast


def test_the_device_is_destroyed_without_a_message():
    volcast.render(builtin="box", builtin_size=8, size=8)
    counts = volcast.shutdown()
    assert counts == {"validating": True, "errors": 0, "warnings": 0}
    assert volcast.render(builtin="box", builtin_size=8, size=8).shape == (8, 8, 4)
