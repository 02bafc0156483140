"""ament_python package smarticle_driver.

Square gait and Maestro servo bridge for smarticle robot boards, plus a board emulator.
"""

from glob import glob

from setuptools import find_packages, setup

package_name = 'smarticle_driver'

setup(
    name=package_name,
    version='0.1.0',
    packages=find_packages(exclude=['test', 'test.*']),
    package_data={package_name: ['py.typed']},
    data_files=[
        ('share/ament_index/resource_index/packages', ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml']),
        ('share/' + package_name + '/config', glob('config/*.yaml')),
    ],
    install_requires=['setuptools'],
    zip_safe=True,
    maintainer='Smarticle stack maintainers',
    maintainer_email='smarticles@example.org',
    description='Square gait and Maestro servo bridge for smarticle robot boards, plus a board emulator.',
    license='Apache-2.0',
    python_requires='>=3.10',
    entry_points={
        'console_scripts': [
            'gait = smarticle_driver.gait_node:main',
            'servo_bridge = smarticle_driver.servo_bridge_node:main',
            'smarticle-fake-board = smarticle_driver.emulator_cli:main',
            'smarticle-board-calibrate = smarticle_driver.calibrate_cli:entry',
            'smarticle-start = smarticle_driver.start_cli:entry',
        ],
    },
)
