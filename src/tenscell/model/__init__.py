"""What a structure is and where it rests: members, coordinates, equilibrium, reference shapes."""
