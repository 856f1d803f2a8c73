"""Physical constants every analysis shares: one value each."""

G = 9.81  # gravity, m/s^2: the paper's value, so that its drop model's figures come out as published
RHO_AIR = 1.225  # air density at sea level and 15 C (ISA), kg/m^3
