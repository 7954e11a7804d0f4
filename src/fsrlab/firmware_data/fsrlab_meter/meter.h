// fsrlab meter: input-capture frequency and duty-cycle meter for the Arduino Uno (ATmega328P, 16 MHz).
// Protocol v3: docs/protocol.md (normative); frames "$TYPE,SEQ,...*CRC\r\n".
#ifndef FSRLAB_METER_H
#define FSRLAB_METER_H

#define METER_FW_VERSION "3.0.0"
#define METER_PROTOCOL_VERSION 3

#ifdef __cplusplus
extern "C" {
#endif

// Runs the meter forever: the edge handlers (capture.S) by interrupt, the protocol in the background.
void meter_run(void) __attribute__((noreturn));

#ifdef __cplusplus
}
#endif

#endif
