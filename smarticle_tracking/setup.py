"""ament_python package smarticle_tracking: Overhead-camera tracker and glider monitor for smarticles."""

from glob import glob

from setuptools import find_packages, setup

package_name = 'smarticle_tracking'

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
    description='Overhead-camera tracker and glider monitor for smarticles.',
    license='Apache-2.0',
    python_requires='>=3.10',
    entry_points={
        'console_scripts': [
            'tracker = smarticle_tracking.tracker_node:main',
            'glider_monitor = smarticle_tracking.glider_monitor_node:main',
            'smarticle-tracker-calibrate = smarticle_tracking.homography_cli:entry',
        ],
    },
)
