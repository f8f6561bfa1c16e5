"""Each task's floor: the default `qd.score_offset` of map-elites (written by
tools/qd_floors.py; do not edit).

The lowest return of 64 random 5x5 robots driven by uniform random actions over the
task's default episode, rounded down to a tenth and never above 0. An elite adds
max(0, fitness - floor) to the QD score, so the score never falls as elites are added.
"""

FLOORS: dict[str, float] = {
    'AreaMaximizer-v0': -3.0,  # lowest random return -2.9866
    'AreaMinimizer-v0': -3.1,  # lowest random return -3.0134
    'Balancer-v0': -3.2,  # lowest random return -3.1506
    'Balancer-v1': -3.4,  # lowest random return -3.3455
    'BeamSlider-v0': -1.5,  # lowest random return -1.4071
    'BeamToppler-v0': -1.2,  # lowest random return -1.1439
    'BidirectionalWalker-v0': -3.5,  # lowest random return -3.4289
    'BridgeWalker-v0': -1.3,  # lowest random return -1.2844
    'Carrier-v0': -2.7,  # lowest random return -2.6586
    'Carrier-v1': -6.1,  # lowest random return -6.0960
    'Catcher-v0': -6.5,  # lowest random return -6.4242
    'CaveCrawler-v0': -1.3,  # lowest random return -1.2965
    'Climber-v0': -0.1,  # lowest random return -0.0946
    'Climber-v1': -0.1,  # lowest random return -0.0991
    'Climber-v2': -0.1,  # lowest random return -0.0964
    'DownStepper-v0': -4.1,  # lowest random return -4.0752
    'Flipper-v0': -1.5,  # lowest random return -1.4401
    'GapJumper-v0': -3.9,  # lowest random return -3.8145
    'HeightMaximizer-v0': -0.1,  # lowest random return -0.0777
    'Hurdler-v0': -4.0,  # lowest random return -3.9091
    'Jumper-v0': -8.9,  # lowest random return -8.8166
    'Lifter-v0': -1.1,  # lowest random return -1.0175
    'ObstacleTraverser-v0': -4.1,  # lowest random return -4.0354
    'ObstacleTraverser-v1': -1.4,  # lowest random return -1.3520
    'PlatformJumper-v0': -6.7,  # lowest random return -6.6607
    'Pusher-v0': -1.3,  # lowest random return -1.2638
    'Pusher-v1': -1.3,  # lowest random return -1.2760
    'Thrower-v0': -1.2,  # lowest random return -1.1270
    'Traverser-v0': -1.6,  # lowest random return -1.5897
    'UpStepper-v0': -3.9,  # lowest random return -3.8386
    'Walker-v0': -0.9,  # lowest random return -0.8425
    'WingspanMazimizer-v0': -2.8,  # lowest random return -2.7600
}
