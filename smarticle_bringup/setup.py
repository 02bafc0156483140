"""ament_python package smarticle_bringup: how the smarticle stack is started."""

from glob import glob

from setuptools import find_packages, setup

package_name = 'smarticle_bringup'

setup(
    name=package_name,
    version='0.1.0',
    packages=find_packages(exclude=['test', 'test.*']),
    package_data={package_name: ['py.typed']},
    data_files=[
        ('share/ament_index/resource_index/packages', ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml']),
        ('share/' + package_name + '/launch', sorted(glob('launch/*.launch.xml'))),
        ('share/' + package_name + '/config', sorted(glob('config/*'))),
    ],
    install_requires=['setuptools'],
    zip_safe=True,
    maintainer='Smarticle stack maintainers',
    maintainer_email='smarticles@example.org',
    description='How the smarticle stack is started: the sim-in-the-loop demo and the tools that join packages.',
    license='Apache-2.0',
    python_requires='>=3.10',
    entry_points={
        'console_scripts': [
            'smarticle-demo = smarticle_bringup.demo:entry',
            'smarticle-launch = smarticle_bringup.launcher:entry',
            'smarticle-compose = smarticle_bringup.compose:entry',
            'smarticle-view = smarticle_bringup.view_node:main',
            'smarticle-sim-camera-calibrate = smarticle_bringup.sim_camera:entry',
        ],
    },
)
