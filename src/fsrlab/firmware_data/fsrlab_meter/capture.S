; fsrlab meter: the edge handlers (Timer1 input capture on D8 = ICP1 = PB0, 62.5 ns ticks).
; Interface and design: capture.h. The rare cases (phases of 2 ms or more, missed edges,
; starvation) are C, in capture.cpp. Cycle counts in comments: lds/sts 2, push/pop 2, sbi/cbi 2.
;
; One visit of the handler: enter (capture interrupt, compare-A wake, or the end of a blind spell),
; serve edges for as long as the next one comes too soon to leave, arm what serves the next edge,
; return. Serving an edge: read ICR1, write the opposite edge select, clear ICF1 (the datasheet's
; order), then check that the pin still shows the level this edge set unless the next edge was
; captured already; otherwise an edge went by unseen (capture_missed counts it and resynchronises).
;
; Registers: r24:r25 and r26:r27 (saved on entry) and nothing else on the fast path. Flags live in
; GPIOR0 (F_* in capture.h), the next edge select in GPIOR1, the edge count of the visit in GPIOR2;
; the rest in capture_state (RAM).

#include <avr/io.h>
#include "capture.h"

#define S capture_state
#define IO(r) _SFR_IO_ADDR(r)
#define MEM(r) _SFR_MEM_ADDR(r)
#define FL IO(GPIOR0)
#define NXT IO(GPIOR1)
#define CNT IO(GPIOR2)

        .section .bss.capture_state,"aw",@nobits
        .global capture_state
        .type capture_state, @object
capture_state:
        .skip CS_SIZE
        .size capture_state, CS_SIZE

        .text

.macro ENTER                            ; 11 cycles
        push r24
        in r24, IO(SREG)
        push r24
        push r25
        push r26
        push r27
.endm

; Call C from the handler: save what ENTER did not and C may clobber (r1 must be zero in C).
.macro CALLC fn, arg=-1
        push r0
        push r1
        push r18
        push r19
        push r20
        push r21
        push r22
        push r23
        push r30
        push r31
        clr r1
.if \arg >= 0
        ldi r22, \arg                   ; second argument (the first, r24:r25, is set already)
.endif
        call \fn
        pop r31
        pop r30
        pop r23
        pop r22
        pop r21
        pop r20
        pop r19
        pop r18
        pop r1
        pop r0
.endm

; Add the 16-bit r24:r25 to a 32-bit sum in RAM (12 cycles when bits 16..31 do not change).
.macro ADD16 at
        lds r26, \at
        add r26, r24
        sts \at, r26
        lds r26, \at+1
        adc r26, r25
        sts \at+1, r26
        brcc 1f
        lds r26, \at+2
        inc r26
        sts \at+2, r26
        brne 1f
        lds r26, \at+3
        inc r26
        sts \at+3, r26
1:
.endm

; ---------------------------------------------------------------------------------------------
        .global __vector_10             ; TIMER1_CAPT: an edge came while the background ran
        .type __vector_10, @function
__vector_10:
        ENTER
        in r26, NXT
        ldi r27, _BV(ICF1) | _BV(OCF1A)
        rjmp got                        ; (the vector cleared ICF1; ICR1 holds the edge)

        .global __vector_11             ; TIMER1_COMPA: the wake armed before an edge that starts a short phase
        .type __vector_11, @function
__vector_11:
        ENTER
        rjmp wait0
; Wait for the capture flag, at most 128 us (Timer0 at clk/8 reaches OCR0A = 255). The flag is
; checked at cycles 0, 2, 4 and 8 of each 11-cycle turn and reaches `got` at most 6 cycles after it
; rises (3 after a sbic, 2 after the sbis); ICES1 is written 6 cycles later: at most 12 cycles
; after the flag, so a phase of 13 cycles or more that begins while the handler polls is caught.
wait:
        in r24, CNT
        cpi r24, EDGE_LIMIT
        brlo wait0
        rjmp starve
wait0:  clr r24
        out IO(TCNT0), r24
        ldi r24, _BV(OCF0A)
        out IO(TIFR0), r24
        in r26, NXT                     ; r26: the edge select to write, r27: the flags to clear
        ldi r27, _BV(ICF1) | _BV(OCF1A) ; (a wake armed for this edge is no longer needed)
w:      sbic IO(TIFR1), ICF1
        rjmp got
        sbic IO(TIFR1), ICF1
        rjmp got
        sbic IO(TIFR1), ICF1
        rjmp got
        sbic IO(TIFR0), OCF0A
        rjmp timeout
        sbis IO(TIFR1), ICF1
        rjmp w
got:    lds r24, MEM(ICR1L)
        lds r25, MEM(ICR1H)             ; (both bytes before the flip: the next capture may come
                                        ; right after it; simavr has no TEMP latch for ICR1)
        sts MEM(TCCR1B), r26            ; the opposite edge from now on
        out IO(TIFR1), r27
        ldi r27, _BV(ICES1)
        eor r26, r27                    ; r26: the polarity just captured (ICES1 set: rising)
        out NXT, r26
        in r27, CNT
        inc r27
        out CNT, r27
        sbrs r26, ICES1
        rjmp fall

; ---- rising edge: ends a low time, completes the open period
rise:   sbis IO(PINB), 0                ; the pin must still be high ...
        rjmp rise_chk
rise_ok:
        sbic FL, F_HALF
        rjmp rise_long
        lds r26, S+CS_PREV
        lds r27, S+CS_PREV+1
        sts S+CS_PREV, r24
        sts S+CS_PREV+1, r25
        sub r24, r26
        sbc r25, r27                    ; low time
        sbis FL, F_PREV
        rjmp 2f
        sts S+CS_PHLO, r24
        sts S+CS_PHLO+1, r25
        sbi FL, F_PLO
        sbis FL, F_HIGH
        rjmp 2f
        ; a complete period: periods += 1, sum_low += low time (its high time is in sum_high)
        lds r26, S+CS_ACC+SUM_N
        inc r26
        sts S+CS_ACC+SUM_N, r26
        brne 3f
        rcall n_carry
3:      ADD16 S+CS_ACC+SUM_LOW
2:      cbi FL, F_HIGH
        sbi FL, F_CHAIN
        sbi FL, F_PREV
        sbic FL, F_REQ                  ; a snapshot wanted: now, no period is open
        rcall snap
        ; next: a high time (ph_hi), then a low time like the one just measured (r24:r25)
        sbis FL, F_PHI
        rjmp wait                       ; nothing to predict from: stay
        sbis FL, F_PLO
        rjmp wait
        tst r25
        brne 8f
        cpi r24, CAPT_SHORT
        brlo 9f
8:      rjmp capt_only
9:
        lds r24, S+CS_PHHI
        lds r25, S+CS_PHHI+1
        rjmp arm_wake

rise_chk:
        sbis IO(TIFR1), ICF1            ; ... unless the falling edge was captured already
        rjmp missed
        rjmp rise_ok

rise_long:                              ; a low time of 2 ms or more (r24:r25 = the capture)
        CALLC capture_long_phase, 1
        rjmp capt_only

; ---- falling edge: ends a high time
fall:   sbic IO(PINB), 0                ; the pin must still be low ...
        rjmp fall_chk
fall_ok:
        sbic FL, F_HALF
        rjmp fall_long
        lds r26, S+CS_PREV
        lds r27, S+CS_PREV+1
        sts S+CS_PREV, r24
        sts S+CS_PREV+1, r25
        sub r24, r26
        sbc r25, r27                    ; high time
        sbis FL, F_PREV
        rjmp 2f
        sts S+CS_PHHI, r24
        sts S+CS_PHHI+1, r25
        sbi FL, F_PHI
        sbis FL, F_CHAIN
        rjmp 2f
        sbi FL, F_HIGH                  ; (the open period's high time is ph_hi)
        ADD16 S+CS_ACC+SUM_HIGH
2:      sbi FL, F_PREV
        ; next: a low time (ph_lo), then a high time like the one just measured (r24:r25)
        sbis FL, F_PHI
        rjmp wait
        sbis FL, F_PLO
        rjmp wait
        tst r25
        brne 8f
        cpi r24, CAPT_SHORT
        brlo 9f
8:      rjmp capt_only
9:
        lds r24, S+CS_PHLO
        lds r25, S+CS_PHLO+1
        rjmp arm_wake

fall_chk:
        sbis IO(TIFR1), ICF1            ; ... unless the rising edge was captured already
        rjmp missed
        rjmp fall_ok

fall_long:
        CALLC capture_long_phase, 0
        rjmp capt_only

; ---- what serves the next edge
capt_only:
        ; the edge after the next one starts a long phase: the next edge may be served late, by
        ; the capture interrupt; if it has come already, serve it now
        sbis IO(TIFR1), ICF1
        rjmp 4f
        in r24, CNT
        cpi r24, EDGE_LIMIT
        brlo 0f
        rjmp starve
0:      in r26, NXT
        ldi r27, _BV(ICF1) | _BV(OCF1A)
        rjmp got
4:      ldi r24, TIMSK_CAPT
        rjmp leave

arm_wake:
        ; r24:r25 = P, the phase until the next edge; the one after is short: be polling when the
        ; next edge comes. Wake at prev + P - P/32 - WAKE_LEAD, if that leaves room to leave.
        sbrc r25, 7
        rjmp capt_only                  ; P >= 32768 ticks: too far for the 16-bit compare
        movw r26, r24                   ; r26:r27 = P >> 5 (swap: >> 4, then one more)
        swap r26
        swap r27
        andi r26, 0x0F
        eor r26, r27
        andi r27, 0x0F
        eor r26, r27
        lsr r27
        ror r26
        subi r26, lo8(-WAKE_LEAD)
        sbci r27, hi8(-WAKE_LEAD)       ; P/32 + WAKE_LEAD
        sub r26, r24
        sbc r27, r25                    ; minus P: the wake's offset from prev, negated
        lds r24, S+CS_PREV
        lds r25, S+CS_PREV+1
        sub r24, r26
        sbc r25, r27                    ; the wake
        tst r25                         ; never 0..SMALL_OCR-1: simavr 1.6 loses compare matches
        brne 7f                         ; just after Timer1 wraps (the hardware does not); wake at
        cpi r24, SMALL_OCR              ; 0xFFFF instead, a little earlier
        brsh 7f
        ldi r24, 0xFF
        ldi r25, 0xFF
7:
        lds r26, MEM(TCNT1L)
        lds r27, MEM(TCNT1H)
        sts MEM(OCR1AH), r25            ; high byte first (TEMP)
        sts MEM(OCR1AL), r24
        sub r24, r26
        sbc r25, r27                    ; room until the wake
        brmi 6f                         ; past already
        subi r24, lo8(EXIT_MIN)
        sbci r25, hi8(EXIT_MIN)
        brcs 6f
        ldi r24, TIMSK_WAKE
        rjmp leave
6:      rjmp wait

timeout:                                ; no edge within 128 us: leave; the next edge comes by the capture interrupt
        ldi r24, TIMSK_CAPT
        rjmp leave

missed:                                 ; an edge went by unseen: count it, resynchronise, stay
        CALLC capture_missed
        rjmp wait

starve:                                 ; EDGE_LIMIT edges back to back, or the background starves
                                        ; (F_STARVE, it clears it): step aside (capture.cpp)
        CALLC capture_blind
        ldi r24, _BV(OCIE1B)            ; no capture interrupt, no wake until capture_resume
        rjmp leave1
; ---- leave: r24 = TIMSK1
leave:  sbic FL, F_STARVE               ; the background starves: step aside instead
        rjmp starve
leave1: sts MEM(TIMSK1), r24
        in r24, CNT
        tst r24
        breq 5f
        ; an edge was served: the half-wraps count from it (compare B at prev + 32768; F_HALF is
        ; clear: the fast path ran with it clear, capture.cpp clears it)
        lds r24, S+CS_PREV+1
        subi r24, 0x80
        sts MEM(OCR1BH), r24
        lds r24, S+CS_PREV
        brne 8f                         ; (Z from subi: the high byte is 0) compare B never below
        cpi r24, SMALL_OCR              ; SMALL_OCR (simavr, see arm_wake); later is harmless here
        brsh 8f
        ldi r24, SMALL_OCR
8:      sts MEM(OCR1BL), r24
        clr r24
        out CNT, r24
5:      pop r27
        pop r26
        pop r25
        pop r24
        out IO(SREG), r24
        pop r24
        reti

; ---- rare helpers
n_carry:                                ; periods += 1, the bytes above the lowest
        lds r26, S+CS_ACC+SUM_N+1
        subi r26, 0xFF
        sts S+CS_ACC+SUM_N+1, r26
        brcs 7f                         ; (subi 0xFF: carry set unless the byte wrapped to 0)
        lds r26, S+CS_ACC+SUM_N+2
        subi r26, 0xFF
        sts S+CS_ACC+SUM_N+2, r26
        brcs 7f
        lds r26, S+CS_ACC+SUM_N+3
        subi r26, 0xFF
        sts S+CS_ACC+SUM_N+3, r26
7:      ret

snap:                                   ; if due: copy the sums (16 bytes), clear F_REQ; keeps r24:r25
        lds r26, MEM(TCNT2)
        lds r27, S+CS_SNAPT
        sub r26, r27
        brpl 1f
        ret                             ; not yet
1:      push r23
        push r30
        push r31
        ldi r26, lo8(S+CS_ACC)
        ldi r27, hi8(S+CS_ACC)
        ldi r30, lo8(S+CS_SNAP)
        ldi r31, hi8(S+CS_SNAP)
        .rept 16
        ld r23, X+
        st Z+, r23
        .endr
        cbi FL, F_REQ
        pop r31
        pop r30
        pop r23
        ret

; ---------------------------------------------------------------------------------------------
; TIMER0_COMPA: the end of a blind spell (capture_blind): count what went by, resynchronise, visit.
        .global __vector_14
        .type __vector_14, @function
__vector_14:
        ENTER
        CALLC capture_resume
        rjmp wait

; TIMER1_COMPB: Timer1 passed prev + 32768 (k+1) ticks without an edge: one more half-wrap.
; Genuine only if TCNT1 is at or just past OCR1B (a flag left from an earlier OCR1B is stale).
        .global __vector_12
        .type __vector_12, @function
__vector_12:
        push r24
        in r24, IO(SREG)
        push r24
        push r25
        push r26
        lds r24, MEM(TCNT1L)
        lds r25, MEM(TCNT1H)
        lds r26, MEM(OCR1BL)
        sub r24, r26
        lds r26, MEM(OCR1BH)
        sbc r25, r26
        brmi 3f                         ; stale
        ldi r24, 1
        sbis FL, F_HALF
        rjmp 1f
        lds r24, S+CS_HALF
        cpi r24, 255
        breq 2f
        inc r24
1:      sts S+CS_HALF, r24
        sbi FL, F_HALF
2:      lds r24, MEM(OCR1BL)            ; OCR1B += 32768
        lds r25, MEM(OCR1BH)
        subi r25, 0x80
        brne 4f
        cpi r24, SMALL_OCR              ; (simavr, see arm_wake; later is harmless here)
        brsh 4f
        ldi r24, SMALL_OCR
4:      sts MEM(OCR1BH), r25
        sts MEM(OCR1BL), r24
3:      pop r26
        pop r25
        pop r24
        out IO(SREG), r24
        pop r24
        reti
