"""The models behind the model contract (fmu_model.h), each a NativeModel: the pendulum
(pendulum.py) and the coupled demo's cart (cart.py), with their variables and C files.

Imports of builder/ core/, fmi/, packaging/ and builder.c_literals; never builder.fmu.
"""
