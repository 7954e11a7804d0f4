"""fsrlab: force sensing with force-sensing resistors read through their piezocapacitance.

Built on A. Matute, L. Paredes-Madrid, G. Moreno, F. Cárdenas, C. A. Palacio, "A Novel and
Inexpensive Approach for Force Sensing Based on FSR Piezocapacitance Aimed at Hysteresis Error
Reduction", Journal of Sensors 2018, 6561901, doi:10.1155/2018/6561901.

All computation is in SI base units (Pa, m, V, A, Ω, F, s, Hz).
"""

__version__ = "0.1.0"
