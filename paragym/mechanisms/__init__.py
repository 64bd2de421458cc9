"""Pure kinematics of the paragym mechanisms: numpy only, no PyBullet, no Gymnasium."""
