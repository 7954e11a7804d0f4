// fsrlab meter: frequency and duty cycle of the LM555 output on D8 (Timer1 input capture, 62.5 ns),
// C_off range switch on D4, op-amp output on A0; framed serial protocol v1 at 115200 baud.
// Matute et al. 2018, J. Sensors 6561901, doi:10.1155/2018/6561901 (paper section 5).
//
// The whole meter lives in meter.cpp: it takes over the MCU (interrupts off, Timer0/1/2, ADC and
// USART programmed directly) because servicing a capture edge within 16 CPU cycles, which a 5 %
// duty cycle at 50 kHz demands, is impossible through an interrupt. See firmware/README.md.
#include "meter.h"

void setup() {
  meter_run();  // never returns
}

void loop() {
}
