// fsrlab meter: frequency and duty cycle of the LM555 output on D8 (Timer1 input capture, 62.5 ns),
// C_off range switch on D4, op-amp output on A0; framed serial protocol v1 at 115200 baud.
// Matute et al. 2018, J. Sensors 6561901, doi:10.1155/2018/6561901 (paper section 5).
//
// The meter lives in meter.cpp (protocol, windows), capture.S and capture.cpp (the edge handlers).
// It takes over the MCU: Timer0, Timer1, Timer2, the ADC and the USART are programmed directly, and
// Arduino's millis(), Serial and analogRead are not used. See firmware/README.md.
#include "meter.h"

void setup() {
  meter_run();  // never returns
}

void loop() {
}
