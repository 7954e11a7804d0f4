"""The virtual device's backpressure (``speed="max"``) counts every byte it has written.

Linux passes bytes written to a pty master to the slave in deferred work, so FIONREAD on the slave can
lag a write (on this kind of machine it did for 18,388 of 20,000 writes read back at once). A device that
checks FIONREAD before each frame then writes past :attr:`VirtualDevice.MAX_UNREAD` whenever that work is
delayed, as on a busy CI machine. Reference: a property that must hold — once ``_write`` returns, the count
the device checks includes the frame, whatever the scheduler did meanwhile.
"""

from fsrlab.acquisition.protocol import encode_frame
from fsrlab.virtual.device import VirtualDevice
from fsrlab.virtual.sources import PhysicsSource


def test_the_unread_count_includes_each_frame_once_written():
    dev = VirtualDevice(PhysicsSource(), seed=1, speed="max")
    dev.open(thread=False)  # no device loop: this test alone writes, and nothing reads the slave
    try:
        initial = dev._unread()  # the boot ID frame, passed on before any check below
        total = initial
        for seq in range(60):  # 60 frames of 41 B stay below the line discipline's 4095-B buffer
            frame = encode_frame("M", seq, (seq * 10, 10, 40, 1234567, 20000, 512, 0, 0))
            dev._write(frame)
            total += len(frame)
            assert dev._unread() == total, f"frame {seq}: the count lags the bytes written"
    finally:
        dev.close()
