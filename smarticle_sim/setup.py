"""ament_python package smarticle_sim: PyBullet smarticle simulation and its sim bridge node."""

from glob import glob

from setuptools import find_packages, setup

package_name = 'smarticle_sim'

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
    description='PyBullet simulation of smarticles and a sim bridge node that publishes the hardware topics.',
    license='Apache-2.0',
    python_requires='>=3.10',
    entry_points={
        'console_scripts': [
            'smarticle-sim = smarticle_sim.cli:main',
            'sim_bridge = smarticle_sim.sim_bridge_node:main',
        ],
        # the sim_world fixture: a lock-step sim and the user's nodes for a test (docs/own_controller.md)
        'pytest11': ['smarticle_sim = smarticle_sim.testing'],
    },
)
